"""Host calls: the only hub code the host writes is a call into `openbricks.host_calls` with data.

A call goes over the wire as one line, `import openbricks.host_calls as h;h.<name>(<key>=<literal>, ...)`,
where every literal is plain data (str, bytes, int, finite float, bool, None, lists, dicts with string
keys), so nothing the host sends is templated source. Each command first hands the hub a fresh tag
(`h.tag('9f2c41d0')`), and the hub answers each call with one frame carrying it,
`@openbricks:<tag> result {json}`: `"ok": true` and the data, or `"ok": false` with `"error"` and
`"type"`. This module encodes calls, separates frames from program output as bytes stream in
(whatever the program printed: see `CallOutput`), and turns a reply into a value or a `HubCallError`.
"""

from __future__ import annotations

import json
import math
import re
import secrets
import zlib
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

from openbricks import host_protocol
from openbricks_server.link.errors import HubCallError, ProtocolError

FRAME_PREFIX = host_protocol.FRAME_PREFIX.encode()
CTRL_D = b"\x04"
TAG_BYTES = 4  # 8 hex digits of nonce per command: no program output will carry it by chance
MAX_FRAME_BYTES = 1 << 20

IMPORT = "import openbricks.host_calls as h"
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


def _call_expression(name: str, data: dict[str, Any]) -> str:
    if not _NAME.match(name):
        raise ValueError(f"host call name {name!r} is not a Python identifier")
    args = []
    for key, value in data.items():
        if not _NAME.match(key):
            raise ValueError(f"{name}: argument name {key!r} is not a Python identifier")
        args.append(f"{key}={python_literal(value, key)}")
    return f"h.{name}({', '.join(args)})"


def call_source(name: str, data: dict[str, Any]) -> str:
    """The one-line command that runs host call `name` with keyword arguments `data` on the hub,
    untagged (its result frame is for a person at the REPL; the host sends `command()`s)."""
    return f"{IMPORT};{_call_expression(name, data)}"


@dataclass(frozen=True)
class Command:
    """Source for the hub's raw REPL, and the tag its host calls frame their results with (None for
    code that is not a host call: nothing in its output is a frame)."""

    source: str | bytes
    tag: str | None = None


def command(*calls: tuple[str, dict[str, Any]]) -> Command:
    """One raw-REPL command running host `calls` in order, under a fresh tag."""
    tag = secrets.token_hex(TAG_BYTES)
    lines = [f"{IMPORT};h.tag({tag!r});{_call_expression(*calls[0])}"]
    lines += [_call_expression(name, data) for name, data in calls[1:]]
    return Command("\n".join(lines), tag)


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


class CallOutput:
    """One command's stdout as it streams in: the program's output, forwarded verbatim as it comes,
    and the hub's frames for the command's tag, kept.

    A frame is `@openbricks:<tag> [again] <kind> [payload]` up to a newline, found anywhere (a
    program's last line may lack its newline): "result" carries a call's JSON reply, "program" says
    the bytes up to the next result frame are the program's, Ctrl-D included. Outside that span the
    first Ctrl-D ends the command's stdout, as the raw REPL frames it. "again" marks a frame the hub
    wrote a second time because a Ctrl-C cut the first: the cut one's bytes are dropped, whether it
    got past its prefix or not. Without a tag (code that is not a host call) nothing is a frame.
    Only bytes that could still be the start of a frame are held back, so output reaches
    `on_output` with at most a frame prefix's length of delay.
    """

    def __init__(self, tag: str | None, on_output: Callable[[bytes], None] | None):
        self._start = FRAME_PREFIX + tag.encode() + b" " if tag else None
        self._on_output = on_output
        self._held = bytearray()
        self._in_frame = False
        self._maybe_cut = b""  # bytes right before a frame that may be a cut first write of it
        self._program = False  # between a program frame and its result frame
        self.ended = False
        self.output = bytearray()
        self.results: list[dict] = []
        #: Bytes and crc32 of what arrived between the program frame and its result frame, to
        #: check against what the hub says its program printed.
        self.program_bytes = 0
        self.program_crc32 = 0

    def feed(self, data: bytes) -> bytes | None:
        """Take the next bytes of the command's stdout; once its end (Ctrl-D) is among them, returns
        what came after it (the error output and the prompt, for the caller), else None."""
        if self.ended:
            raise ProtocolError("the command's output already ended")
        self._held += data
        while True:
            if self._in_frame:
                if not self._frame_step():
                    return None
                continue
            at = self._held.find(self._start) if self._start else -1
            end = -1 if self._program else self._held.find(CTRL_D)
            if end >= 0 and (at < 0 or end < at):
                self._forward(self._held[:end])
                rest = bytes(self._held[end + 1 :])
                self._held.clear()
                self.ended = True
                return rest
            if at >= 0:
                before = bytes(self._held[:at])
                cut = _prefix_tail(before, self._start)
                self._forward(before[: len(before) - cut])
                self._maybe_cut = before[len(before) - cut :]
                del self._held[:at]
                self._in_frame = True
                continue
            keep = _undecided_tail(self._held, self._start) if self._start else 0
            self._forward(self._held[: len(self._held) - keep])
            del self._held[: len(self._held) - keep]
            return None

    def _frame_step(self) -> bool:
        """Consume a complete frame at the head of the held bytes; False while it is incomplete."""
        newline = self._held.find(b"\n")
        again = self._held.find(self._start, 1)  # the hub began the frame again after a Ctrl-C
        cut = self._held.find(CTRL_D)  # the command ended inside a frame: the frame is lost
        firsts = [i for i in (again, cut) if i >= 0 and (newline < 0 or i < newline)]
        if firsts:
            del self._held[: min(firsts)]
            self._forward(self._maybe_cut)
            self._maybe_cut = b""
            self._in_frame = False
            return True
        if newline < 0:
            if len(self._held) > MAX_FRAME_BYTES:
                raise ProtocolError(
                    f"a host-call frame longer than {MAX_FRAME_BYTES} bytes: {bytes(self._held[:80])!r}"
                )
            return False
        line = bytes(self._held[len(self._start) : newline]).rstrip(b"\r")
        del self._held[: newline + 1]
        self._in_frame = False
        kind, _, payload = line.partition(b" ")
        if kind == b"again":
            kind, _, payload = payload.partition(b" ")
        else:
            self._forward(self._maybe_cut)
        self._maybe_cut = b""
        if kind == b"program":
            self._program = True
        elif kind == b"result":
            text = payload.decode("utf-8", "replace")
            try:
                self.results.append(json.loads(text))
            except json.JSONDecodeError as err:
                raise ProtocolError(f"unreadable host-call result {text[:120]!r}: {err}") from None
            self._program = False
        else:
            raise ProtocolError(f"unknown frame {line[:80]!r} from the hub's host calls")
        return True

    def _forward(self, data: bytes | bytearray) -> None:
        if not data:
            return
        data = bytes(data)
        self.output += data
        if self._program:
            self.program_bytes += len(data)
            self.program_crc32 = zlib.crc32(data, self.program_crc32)
        if self._on_output is not None:
            self._on_output(data)


def _prefix_tail(buffer: bytes | bytearray, marker: bytes) -> int:
    """Length of the longest tail of `buffer` that is a proper prefix of `marker`."""
    for n in range(min(len(marker) - 1, len(buffer)), 0, -1):
        if buffer.endswith(marker[:n]):
            return n
    return 0


def _undecided_tail(buffer: bytes | bytearray, start: bytes) -> int:
    """Length of the tail of `buffer` that may still turn out to be the hub's: the beginning of a
    frame, possibly behind the first bytes of a frame a Ctrl-C cut (decided when it completes)."""
    best = 0
    for begun in range(min(len(start) - 1, len(buffer)), -1, -1):
        if begun and not buffer.endswith(start[:begun]):
            continue
        best = max(best, begun + _prefix_tail(buffer[: len(buffer) - begun], start))
    return best


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
    #: How the hub's latest run ended (launcher.last_run()), or None.
    last_run: dict | None
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
            last_run=result.get("last_run"),
            raw=dict(result),
        )
