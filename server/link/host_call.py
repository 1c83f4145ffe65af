"""Host calls: the only hub code the host writes is a call into `openbricks.host_calls` with data.

A call goes over the wire as one line, `import openbricks.host_calls as h;h.<name>(<key>=<literal>, ...)`,
where every literal is plain data (str, bytes, int, finite float, bool, None, lists, dicts with string
keys), so nothing the host sends is templated source. The hub answers with exactly one line,
`@openbricks-result {json}`: `"ok": true` and the data, or `"ok": false` with `"error"` and `"type"`.
This module encodes calls, separates result lines from program output as bytes stream in, and turns a
reply into a value or a `HubCallError`.
"""

from __future__ import annotations

import json
import math
import re
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

from openbricks_server.link.errors import HubCallError, ProtocolError

RESULT_MARKER = b"@openbricks-result "

_NAME = re.compile(r"^[A-Za-z_][A-Za-z0-9_]*$")


def python_literal(value: Any, where: str = "argument") -> str:
    """`value` as MicroPython source: only data (str, int, float, bool, None, lists, dicts)."""
    if value is None or isinstance(value, bool | int | str | bytes):
        return repr(value)
    if isinstance(value, float):
        if not math.isfinite(value):
            raise ValueError(f"{where}={value!r}: only finite numbers can be sent to the hub")
        return repr(value)
    if isinstance(value, list | tuple):
        inner = ", ".join(python_literal(v, where) for v in value)
        return f"[{inner}]"
    if isinstance(value, dict):
        items = []
        for key, v in value.items():
            if not isinstance(key, str):
                raise ValueError(f"{where}: dictionary keys sent to the hub must be strings, not {key!r}")
            items.append(f"{key!r}: {python_literal(v, where)}")
        return "{" + ", ".join(items) + "}"
    raise ValueError(f"{where}={value!r}: a {type(value).__name__} cannot be sent to the hub as data")


def call_source(name: str, data: dict[str, Any]) -> str:
    """The one-line command that runs host call `name` with keyword arguments `data` on the hub."""
    if not _NAME.match(name):
        raise ValueError(f"host call name {name!r} is not a Python identifier")
    args = []
    for key, value in data.items():
        if not _NAME.match(key):
            raise ValueError(f"{name}: argument name {key!r} is not a Python identifier")
        args.append(f"{key}={python_literal(value, key)}")
    return f"import openbricks.host_calls as h;h.{name}({', '.join(args)})"


def check_reply(hub: str, name: str, reply: dict) -> dict:
    """`reply` itself when the hub reported success; HubCallError with the hub's reason otherwise."""
    if not reply.get("ok", False):
        raise HubCallError(hub, name, str(reply.get("type", "Error")), str(reply.get("error", "")))
    return reply


def single_result(hub: str, name: str, results: list[dict], stdout: bytes) -> dict:
    """The reply of one call from the result lines its command printed (every one must be ok)."""
    if not results:
        shown = stdout[-200:].decode("utf-8", "replace")
        raise ProtocolError(
            f"{name} on {hub} printed no result line (is openbricks.host_calls on it?); output: {shown!r}"
        )
    for reply in results:
        check_reply(hub, name, reply)
    return results[-1]


class ResultLines:
    """Splits a command's stdout into program output (forwarded as it comes) and result lines (kept).

    A line is held back only while it could still turn out to be a result line, so program output
    reaches `on_output` with at most a marker's length of delay.
    """

    def __init__(self, on_output: Callable[[bytes], None] | None):
        self._on_output = on_output
        self._line = bytearray()
        self._forwarded = 0  # bytes of the current line already forwarded
        self.output = bytearray()
        self.results: list[dict] = []

    def feed(self, data: bytes) -> None:
        start = 0
        while True:
            newline = data.find(b"\n", start)
            if newline < 0:
                self._line += data[start:]
                self._flush_safe()
                return
            self._line += data[start : newline + 1]
            self._end_line()
            start = newline + 1

    def finish(self) -> None:
        """The command ended: a last line without a newline is program output."""
        if self._line:
            self._forward(bytes(self._line[self._forwarded :]))
            self._line.clear()
            self._forwarded = 0

    def _could_be_result(self) -> bool:
        return self._forwarded == 0 and RESULT_MARKER.startswith(bytes(self._line[: len(RESULT_MARKER)]))

    def _flush_safe(self) -> None:
        if self._could_be_result():
            return
        self._forward(bytes(self._line[self._forwarded :]))
        self._forwarded = len(self._line)

    def _end_line(self) -> None:
        if self._forwarded == 0 and self._line.startswith(RESULT_MARKER):
            text = self._line[len(RESULT_MARKER) :].decode("utf-8", "replace").strip()
            try:
                self.results.append(json.loads(text))
            except json.JSONDecodeError as err:
                raise ProtocolError(f"unreadable host-call result line {text[:120]!r}: {err}") from None
        else:
            self._forward(bytes(self._line[self._forwarded :]))
        self._line.clear()
        self._forwarded = 0

    def _forward(self, data: bytes) -> None:
        if not data:
            return
        self.output += data
        if self._on_output is not None:
            self._on_output(data)


@dataclass(frozen=True)
class HubInfo:
    """The hub's `info` call: firmware label, chip, runtime, and what it accepts."""

    firmware: str
    version: str
    runtime: str
    chip: str | None
    accepts_mpy: bool
    mpy_version: int | None
    program_path: str
    max_program_bytes: int
    compression: tuple[str, ...]
    running: bool
    raw: dict

    @classmethod
    def from_result(cls, result: dict) -> HubInfo:
        return cls(
            firmware=str(result.get("firmware", "")),
            version=str(result.get("version", "")),
            runtime=str(result.get("runtime", "")),
            chip=result.get("chip"),
            accepts_mpy=bool(result.get("accepts_mpy", False)),
            mpy_version=result.get("mpy_version"),
            program_path=str(result.get("program_path", "/program.mpy")),
            max_program_bytes=int(result.get("max_program_bytes", 0)),
            compression=tuple(result.get("compression", ())),
            running=bool(result.get("running", False)),
            raw=dict(result),
        )
