"""The raw-REPL client: MicroPython's program channel, spoken over any `Link`.

The protocol, as the hub's `pyexec.c` implements it:
- Ctrl-A enters the raw REPL (`raw REPL; CTRL-B to exit\\r\\n>`), Ctrl-B leaves it, Ctrl-C interrupts
  what runs, Ctrl-D on an empty line soft-resets (`OK\\r\\nMPY: soft reboot\\r\\n`, then the banner).
- Plain raw: source, Ctrl-D -> `OK`, stdout, `\\x04`, stderr (a traceback), `\\x04`, `>`. It has no flow
  control, so it is only the fallback for a hub that refuses raw-paste.
- Raw-paste: `\\x05A\\x01` -> `R\\x01`, the window W (16-bit little endian) and `\\x01`. The host may
  have W bytes in flight per `\\x01` received (the first two arrive together: 2W to start), so the
  hub never buffers more than 2W. Ctrl-D ends the data, the hub acknowledges with `\\x04` and then
  answers as in plain raw (without the `OK`). `R\\x00` means the hub has it switched off.

Throughput is window / round trip (see `put`). Program output is handed to `on_output` as it
arrives; host calls (`openbricks.host_calls` on the hub) print exactly one result line,
`@openbricks-result {json}`, which is parsed and never shown as program output.
"""

from __future__ import annotations

import asyncio
import base64
import json
import math
import re
import struct
import zlib
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Any

from openbricks_server.link.base import Link
from openbricks_server.link.errors import (
    HubCallError,
    HubException,
    LinkDropped,
    LinkError,
    LinkTimeout,
    ProtocolError,
)

CTRL_A, CTRL_B, CTRL_C, CTRL_D = b"\x01", b"\x02", b"\x03", b"\x04"
RAW_BANNER = b"raw REPL; CTRL-B to exit\r\n"
SOFT_REBOOT = b"soft reboot\r\n"
PASTE_ENTER = b"\x05A\x01"
RESULT_MARKER = b"@openbricks-result "

DEFAULT_TIMEOUT_S = 10.0
ENTER_RETRY_S = 1.0  # a booting hub can miss the first Ctrl-C / Ctrl-A: they are sent again this often
QUIET_S = 0.3  # silence that means a hub has answered every request sent so far
DEFAULT_RUN_TIMEOUT_S = 600.0
PLAIN_RAW_CHUNK_BYTES = 256  # the stock hub's stdin ring holds 260: no flow control without raw-paste
PLAIN_RAW_PACE_S = 0.01

# Staging: how much base64 text one raw-paste command may carry. The hub's lexer holds the whole
# string literal while it parses, then the str and the decoded bytes live next to it, so this bounds
# the hub's RAM per call (~30 KB at 12 KB, on a hub with ~100 KB free). A .mpy up to ~14 KB
# (compressing to 0.64) goes in one call; larger ones take one more command, pipelined.
DEFAULT_CALL_PAYLOAD_CHARS = 12 * 1024
# zlib window for staged payloads: the hub's inflater allocates 2**wbits bytes. 2 KB costs a few
# percent of ratio against 32 KB on .mpy files and keeps the hub's allocation small.
ZLIB_WBITS = 11
# Compression is used when it saves at least this fraction of the bytes on the wire.
COMPRESSION_MIN_SAVING = 0.05


@dataclass
class ExecResult:
    """What one command printed: stdout (minus host-call result lines) and stderr (a traceback)."""

    stdout: bytes
    stderr: bytes
    results: list[dict] = field(default_factory=list)


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


@dataclass(frozen=True)
class LinkEvent:
    """A change of the link during a long command: "dropped" (with the reason) or "reconnected"."""

    kind: str
    hub: str
    detail: str = ""


class _ResultLines:
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

    def _is_result(self) -> bool:
        return self._line.startswith(RESULT_MARKER)

    def _could_be_result(self) -> bool:
        return RESULT_MARKER.startswith(bytes(self._line[: len(RESULT_MARKER)])) and self._forwarded == 0

    def _flush_safe(self) -> None:
        if self._could_be_result():
            return
        self._forward(bytes(self._line[self._forwarded :]))
        self._forwarded = len(self._line)

    def _end_line(self) -> None:
        if self._forwarded == 0 and self._is_result():
            text = self._line[len(RESULT_MARKER) :].decode("utf-8", "replace").strip()
            try:
                self.results.append(json.loads(text))
            except json.JSONDecodeError as err:
                raise ProtocolError(f"unreadable host-call result line {text[:120]!r}: {err}") from None
        else:
            self._forward(bytes(self._line[self._forwarded :]))
        self._line.clear()
        self._forwarded = 0

    def finish(self) -> None:
        if self._line:
            self._forward(bytes(self._line[self._forwarded :]))
            self._line.clear()
            self._forwarded = 0

    def _forward(self, data: bytes) -> None:
        if not data:
            return
        self.output += data
        if self._on_output is not None:
            self._on_output(data)


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


class RawRepl:
    """The raw-REPL session on one link. Not safe for two commands at once: one caller at a time
    (the daemon serialises commands per hub); `interrupt()` is the exception, it may be sent any time.
    """

    def __init__(
        self,
        link: Link,
        *,
        timeout_s: float = DEFAULT_TIMEOUT_S,
        use_raw_paste: bool = True,
        send_ahead: bool = False,
    ):
        self.link = link
        self.hub = link.hub
        self.timeout_s = timeout_s
        #: Bytes per raw-paste flow-control window, as the hub granted it (None until the first paste).
        self.paste_window: int | None = None
        self._raw_paste = use_raw_paste
        #: Send a command's first two windows along with its paste request (see exec_many).
        self.send_ahead = send_ahead
        self._prompt_pending = False
        self.info_cache: HubInfo | None = None

    # -- session --------------------------------------------------------------------------------

    async def enter(
        self, *, soft_reset: bool = False, timeout_s: float | None = None, retry_s: float = ENTER_RETRY_S
    ) -> None:
        """Stop whatever runs and enter the raw REPL, from any state (friendly REPL, raw, mid-paste,
        a program running). A hub still booting may miss the request: it is repeated every
        `retry_s` until the banner comes or `timeout_s` runs out."""
        timeout_s = self.timeout_s if timeout_s is None else timeout_s
        loop = asyncio.get_running_loop()
        deadline = loop.time() + timeout_s
        attempts = 0
        while True:
            attempts += 1
            await self.link.write(b"\r" + CTRL_C + CTRL_C)
            await self.link.write(b"\r" + CTRL_A)
            wait_s = min(retry_s, deadline - loop.time())
            try:
                await self.link.read_until(RAW_BANNER + b">", "the raw REPL banner", max(wait_s, 0))
                break
            except LinkTimeout:
                if loop.time() >= deadline:
                    raise LinkTimeout("the raw REPL banner", self.hub, timeout_s) from None
        if attempts > 1:
            # Earlier requests may still be answered: let those banners arrive, drop them, ask once more.
            await self._discard_until_quiet(QUIET_S, deadline)
            await self.link.write(CTRL_A)
            await self.link.read_until(
                RAW_BANNER + b">", "the raw REPL banner", max(deadline - loop.time(), 0)
            )
        self._prompt_pending = False
        if soft_reset:
            await self.soft_reset(timeout_s=timeout_s)

    async def _discard_until_quiet(self, quiet_s: float, deadline: float) -> None:
        loop = asyncio.get_running_loop()
        while loop.time() < deadline:
            try:
                await self.link.read_some("silence", min(quiet_s, max(deadline - loop.time(), 0)))
            except LinkTimeout:
                return

    async def soft_reset(self, *, timeout_s: float | None = None) -> None:
        """Ctrl-D on an empty raw-REPL line: the hub restarts its VM and comes back in the raw REPL."""
        timeout_s = self.timeout_s if timeout_s is None else timeout_s
        await self._await_prompt(timeout_s)
        await self.link.write(CTRL_D)
        await self.link.read_until(SOFT_REBOOT, "the soft-reboot notice", timeout_s)
        await self.link.read_until(RAW_BANNER, "the raw REPL banner after a soft reboot", timeout_s)
        self._prompt_pending = True

    async def exit(self) -> None:
        """Back to the friendly REPL (Ctrl-B)."""
        await self.link.write(CTRL_B)
        self._prompt_pending = False

    async def interrupt(self) -> None:
        """Ctrl-C: raises KeyboardInterrupt in what runs on the hub (its output still follows)."""
        await self.link.write(CTRL_C)

    async def _await_prompt(self, timeout_s: float) -> None:
        if self._prompt_pending:
            await self.link.read_until(b">", "the raw REPL prompt", timeout_s)
            self._prompt_pending = False

    # -- executing code -------------------------------------------------------------------------

    async def exec(
        self,
        source: str | bytes,
        *,
        on_output: Callable[[bytes], None] | None = None,
        timeout_s: float | None = None,
    ) -> ExecResult:
        """Run `source` on the hub; raises HubException with the hub's traceback if it raised."""
        result = (await self.exec_many([source], on_output=on_output, timeout_s=timeout_s))[0]
        return result

    async def exec_many(
        self,
        sources: Sequence[str | bytes],
        *,
        on_output: Callable[[bytes], None] | None = None,
        timeout_s: float | None = None,
        follow_drops: bool = False,
        on_link_event: Callable[[LinkEvent], None] | None = None,
        stop_when: Callable[[ExecResult], bool] | None = None,
    ) -> list[ExecResult]:
        """Run several commands back to back, pipelined to spare round trips.

        Raw-paste costs a round trip before the data (request, then the hub's grant) and one after
        (end, then the answer). The next command's request rides behind the previous command's end,
        so its grant comes back with the previous answer instead of costing a round trip of its own.
        With `send_ahead` (off by default), once the window is known from an earlier grant in this
        session, a command's first two windows also go out right behind its request: a hub's stdin
        ring holds them (it is sized for two windows plus a few bytes, and is empty then), but a
        hub model that only credits bytes sent after the grant was seen counts them as overrun.

        Stops at the first command that raises on the hub (HubException), or after the first result
        `stop_when(result)` is true for (returning the results so far); a command already requested
        behind it is cancelled with Ctrl-C before it compiles, so none of it runs.
        With `follow_drops`, a link that drops while a command runs is reconnected and the
        command's output followed on (the hub keeps it meanwhile); otherwise LinkDropped.
        """
        timeout_s = self.timeout_s if timeout_s is None else timeout_s
        blobs = [s.encode() if isinstance(s, str) else bytes(s) for s in sources]
        results = []
        requested = False  # the current command's paste request went out with the previous end
        early = 0  # bytes of the current command sent along with its request
        for index, blob in enumerate(blobs):
            await self._await_prompt(timeout_s)
            if not requested and self._raw_paste:
                early = self._early_length(blob)
                await self.link.write(PASTE_ENTER + blob[:early], timeout_s)
                requested = True
            window = await self._read_paste_grant(timeout_s, early) if requested else None
            if window is None:
                await self._send_plain_raw(blob, timeout_s)
                requested, early = False, 0
            else:
                following = blobs[index + 1] if index + 1 < len(blobs) else None
                requested, early = await self._send_paste(blob, window, early, following, timeout_s)
            result = await self._follow(on_output, timeout_s, follow_drops, on_link_event)
            if result.stderr:
                if requested:
                    await self._cancel_requested_paste(early, timeout_s)
                else:
                    await self._await_prompt(timeout_s)
                raise HubException(
                    self.hub, result.stderr.decode("utf-8", "replace"), result.stdout, result.results
                )
            results.append(result)
            if stop_when is not None and stop_when(result) and requested:
                await self._cancel_requested_paste(early, timeout_s)
                break
        await self._await_prompt(timeout_s)
        return results

    def _early_length(self, blob: bytes) -> int:
        """How much of a command may go out with its paste request: the 2 windows the grant will
        give, once a grant in this session told the window (0 before, or with `send_ahead` off)."""
        if not self.send_ahead or self.paste_window is None:
            return 0
        return min(len(blob), 2 * self.paste_window)

    async def _read_paste_grant(self, timeout_s: float, early: int = 0) -> int | None:
        """The hub's answer to `\\x05A\\x01`: the window size, or None if it only speaks plain raw."""
        head = await self.link.read_exactly(2, "the raw-paste reply", timeout_s)
        if head == b"R\x01":
            raw = await self.link.read_exactly(2, "the raw-paste window", timeout_s)
            (window,) = struct.unpack("<H", raw)
            if window == 0:
                raise ProtocolError(f"{self.hub} granted a raw-paste window of 0 bytes")
            self.paste_window = window
            return window
        self._raw_paste = False
        if head == b"R\x00":
            await self.link.read_until(b">", "the raw REPL prompt after a refused raw-paste", timeout_s)
        else:
            # A runtime without raw-paste takes the request as text plus a Ctrl-A: it re-prints the banner.
            await self.link.read_until(RAW_BANNER + b">", "the raw REPL banner", timeout_s)
        if early:
            await self.link.write(CTRL_C, timeout_s)  # the early bytes landed on the raw line: clear it
        return None

    async def _send_paste(
        self, data: bytes, window: int, early: int, following: bytes | None, timeout_s: float
    ) -> tuple[bool, int]:
        """Stream the rest of `data` within the hub's windows and end it, requesting the `following`
        command's paste (with its early bytes) in the same write. Returns (next requested, its
        early bytes); (False, 0) when the hub cut the paste short."""
        credit = window - early  # the window is the first grant; its trailing \x01 the second
        sent = early
        while sent < len(data):
            credit, cut_short = self._absorb_flow_control(credit, window)
            if cut_short:
                await self.link.write(CTRL_D)  # acknowledge the hub's abrupt end, then read its error
                return False, 0
            if credit <= 0:
                await self._wait_flow_control(sent, len(data), timeout_s)
                continue
            n = min(credit, len(data) - sent)
            await self.link.write(data[sent : sent + n], timeout_s)
            sent += n
            credit -= n
        tail = CTRL_D
        next_early = 0
        if following is not None:
            next_early = self._early_length(following)
            tail += PASTE_ENTER + following[:next_early]
        await self.link.write(tail, timeout_s)
        await self._read_paste_ack(timeout_s)
        return following is not None, next_early

    async def _read_paste_ack(self, timeout_s: float) -> None:
        ack = await self.link.read_until(CTRL_D, "the end-of-paste acknowledgement", timeout_s)
        if ack.strip(CTRL_A):
            raise ProtocolError(
                f"{self.hub} sent {ack[:40]!r} during a raw-paste upload instead of flow control"
            )

    def _absorb_flow_control(self, credit: int, window: int) -> tuple[int, bool]:
        """Take every flow-control byte already received: returns (credit, hub ended the paste)."""
        while self.link.available():
            byte = self.link.take(1)
            if byte == CTRL_A:
                credit += window
            elif byte == CTRL_D:
                return credit, True
            else:
                raise ProtocolError(
                    f"{self.hub} sent {byte!r} during a raw-paste upload instead of flow control"
                )
        return credit, False

    async def _wait_flow_control(self, sent: int, total: int, timeout_s: float) -> None:
        what = f"a raw-paste window (after {sent} of {total} bytes)"
        try:
            await self.link.wait_readable(what, timeout_s)
        except LinkDropped as drop:
            raise LinkDropped(self.hub, drop.reason, f"uploading ({sent} of {total} bytes sent)") from None

    async def _send_plain_raw(self, data: bytes, timeout_s: float) -> None:
        for start in range(0, len(data), PLAIN_RAW_CHUNK_BYTES):
            await self.link.write(data[start : start + PLAIN_RAW_CHUNK_BYTES], timeout_s)
            await asyncio.sleep(PLAIN_RAW_PACE_S)
        await self.link.write(CTRL_D, timeout_s)
        ok = await self.link.read_exactly(2, "the raw REPL's OK", timeout_s)
        if ok != b"OK":
            raise ProtocolError(f"{self.hub} answered {ok!r} instead of OK to a raw REPL command")

    async def _cancel_requested_paste(self, early: int, timeout_s: float) -> None:
        """A command was requested behind one that failed: Ctrl-C ends its paste before it compiles."""
        await self._await_prompt(timeout_s)
        window = await self._read_paste_grant(timeout_s, early)
        if window is None:
            return
        await self.link.write(CTRL_C, timeout_s)
        await self._read_paste_ack(timeout_s)
        await self._follow(None, timeout_s, False, None)
        await self._await_prompt(timeout_s)

    async def _follow(
        self,
        on_output: Callable[[bytes], None] | None,
        timeout_s: float,
        follow_drops: bool,
        on_link_event: Callable[[LinkEvent], None] | None,
    ) -> ExecResult:
        lines = _ResultLines(on_output)
        await self._read_resilient(
            CTRL_D, "the command's output", timeout_s, lines.feed, follow_drops, on_link_event
        )
        lines.finish()
        stderr = bytearray()
        await self._read_resilient(
            CTRL_D, "the command's error output", timeout_s, stderr.extend, follow_drops, on_link_event
        )
        self._prompt_pending = True
        return ExecResult(bytes(lines.output), bytes(stderr), lines.results)

    async def _read_resilient(
        self,
        marker: bytes,
        what: str,
        timeout_s: float,
        on_data: Callable[[bytes], None],
        follow_drops: bool,
        on_link_event: Callable[[LinkEvent], None] | None,
    ) -> None:
        loop = asyncio.get_running_loop()
        deadline = loop.time() + timeout_s
        while True:
            remaining = deadline - loop.time()
            if remaining <= 0:
                raise LinkTimeout(what, self.hub, timeout_s)
            try:
                await self.link.read_until(marker, what, remaining, on_data=on_data)
                return
            except LinkTimeout:
                raise LinkTimeout(what, self.hub, timeout_s) from None
            except LinkDropped as drop:
                if not (follow_drops and self.link.can_reconnect):
                    raise
                if on_link_event is not None:
                    on_link_event(LinkEvent("dropped", self.hub, drop.reason))
                await self.link.reconnect(max(deadline - loop.time(), 0.001))
                if on_link_event is not None:
                    on_link_event(LinkEvent("reconnected", self.hub))

    # -- host calls -----------------------------------------------------------------------------

    async def call(
        self,
        name: str,
        *,
        on_output: Callable[[bytes], None] | None = None,
        timeout_s: float | None = None,
        **data: Any,
    ) -> dict:
        """Run host call `name(**data)` on the hub and return its result (raises HubCallError on failure)."""
        result = await self.exec(call_source(name, data), on_output=on_output, timeout_s=timeout_s)
        return self._single_result(name, result)

    def _single_result(self, name: str, result: ExecResult) -> dict:
        if not result.results:
            shown = result.stdout[-200:].decode("utf-8", "replace")
            raise ProtocolError(
                f"{name} on {self.hub} printed no result line (is openbricks.host_calls on it?); "
                f"output: {shown!r}"
            )
        for reply in result.results:
            self._check_ok(name, reply)
        return result.results[-1]

    def _check_ok(self, name: str, reply: dict) -> None:
        if not reply.get("ok", False):
            raise HubCallError(self.hub, name, str(reply.get("type", "Error")), str(reply.get("error", "")))

    async def info(self, *, timeout_s: float | None = None) -> HubInfo:
        """The hub's firmware, runtime and capabilities (kept in `info_cache` for later choices)."""
        self.info_cache = HubInfo.from_result(await self.call("info", timeout_s=timeout_s))
        return self.info_cache

    async def set_rtc(self, epoch_ms: int, *, timeout_s: float | None = None) -> dict:
        return await self.call("set_rtc", epoch_ms=int(epoch_ms), timeout_s=timeout_s)

    async def run(
        self,
        path: str | None = None,
        *,
        on_output: Callable[[bytes], None] | None = None,
        on_link_event: Callable[[LinkEvent], None] | None = None,
        timeout_s: float = DEFAULT_RUN_TIMEOUT_S,
    ) -> dict:
        """Run the staged program through the hub's launcher, streaming its output.

        A link that drops meanwhile is reported through `on_link_event` as soon as the transport
        notices, reconnected, and followed on: the hub keeps the program's output while nobody
        listens, so none is lost. A stop (Ctrl-C, the program button) is an outcome, not an error.
        """
        data = {} if path is None else {"path": path}
        await self._await_prompt(self.timeout_s)
        try:
            (result,) = await self.exec_many(
                [call_source("run", data)],
                on_output=on_output,
                timeout_s=timeout_s,
                follow_drops=True,
                on_link_event=on_link_event,
            )
        except HubException as exc:
            # A stopped run prints its result, then lets KeyboardInterrupt through.
            if exc.results and "KeyboardInterrupt" in exc.traceback:
                return self._single_result("run", ExecResult(exc.stdout, b"", exc.results))
            raise
        return self._single_result("run", result)

    # -- files ----------------------------------------------------------------------------------

    def _hub_accepts_zlib(self) -> bool:
        return self.info_cache is not None and "zlib" in self.info_cache.compression

    async def put(
        self,
        path: str,
        data: bytes,
        *,
        compress: bool | None = None,
        call_payload_chars: int = DEFAULT_CALL_PAYLOAD_CHARS,
        timeout_s: float | None = None,
    ) -> dict:
        """Store `data` at `path` on the hub atomically (verified size and crc32 before the rename).

        On the wire: zlib (2 KB window) when the hub has `deflate` and it saves bytes, then base64
        (raw-REPL input is text and a hub call takes data, not code); one `stage` call when the text
        fits `call_payload_chars`, else `stage_begin` + first chunk, middle chunks, last chunk +
        `stage_end`, pipelined. Upload speed is min(link, 2 windows per round trip): with the
        stock 128-byte window a BLE link at 7.5 ms gives ~17 KB/s, with 2 KB windows the link
        itself is the limit (benchmarks/link_upload.py measures both).

        `compress=None` compresses when `info()` said the hub can inflate (call `info()` first).
        """
        if compress is None:
            compress = self._hub_accepts_zlib()
        payload, compression = data, None
        if compress:
            packer = zlib.compressobj(9, zlib.DEFLATED, ZLIB_WBITS)
            packed = packer.compress(data) + packer.flush()
            if len(packed) <= len(data) * (1 - COMPRESSION_MIN_SAVING):
                payload, compression = packed, "zlib"
        text = base64.b64encode(payload).decode("ascii")
        size, crc = len(data), zlib.crc32(data)
        if len(text) <= call_payload_chars:
            sources = [
                call_source(
                    "stage",
                    {
                        "payload": text,
                        "path": path,
                        "encoding": "base64",
                        "compression": compression,
                        "size": size,
                        "crc32": crc,
                    },
                )
            ]
        else:
            chunks = [text[i : i + call_payload_chars] for i in range(0, len(text), call_payload_chars)]
            sources = []
            for index, chunk in enumerate(chunks):
                parts = []
                if index == 0:
                    parts.append(call_source("stage_begin", {"path": path}))
                parts.append(call_source("stage_append", {"payload": chunk}))
                if index == len(chunks) - 1:
                    parts.append(
                        call_source("stage_end", {"compression": compression, "size": size, "crc32": crc})
                    )
                sources.append("\n".join(parts))
        try:
            results = await self.exec_many(
                sources,
                timeout_s=timeout_s,
                stop_when=lambda result: any(not reply.get("ok", False) for reply in result.results),
            )
        except LinkDropped as drop:
            raise LinkDropped(self.hub, drop.reason, f"uploading {path} ({size} bytes)") from None
        replies = [reply for result in results for reply in result.results]
        for reply in replies:
            self._check_ok("stage", reply)
        final = replies[-1] if replies else {}
        if final.get("bytes") != size or final.get("crc32") != crc:
            raise ProtocolError(
                f"{self.hub} confirmed {final!r} for {path}; expected {size} bytes, crc32 {crc}"
            )
        return final

    async def get(self, path: str, *, block_bytes: int = 2048, timeout_s: float | None = None) -> bytes:
        """Read file `path` from the hub (base64 blocks through MicroPython's own `open`)."""
        out = bytearray()
        while True:
            source = (
                "import binascii\n"
                f"f=open({path!r},'rb')\n"
                f"f.seek({len(out)})\n"
                f"print(binascii.b2a_base64(f.read({int(block_bytes)})).decode().strip())\n"
                "f.close()\n"
            )
            try:
                result = await self.exec(source, timeout_s=timeout_s)
            except HubException as exc:
                if len(out) == 0 and ("OSError" in exc.traceback or "ENOENT" in exc.traceback):
                    raise LinkError(
                        f"{self.hub} has no readable file {path}: {exc.traceback.strip().splitlines()[-1]}"
                    ) from None
                raise
            block = base64.b64decode(result.stdout.strip())
            out += block
            if len(block) < block_bytes:
                return bytes(out)
