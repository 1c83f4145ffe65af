"""The raw-REPL session: MicroPython's program channel on one `Link`, as the hub's `pyexec.c` speaks it.

- Ctrl-A enters the raw REPL (`raw REPL; CTRL-B to exit\\r\\n>`), Ctrl-B leaves it, Ctrl-C interrupts
  what runs, Ctrl-D on an empty line soft-resets (`OK\\r\\nMPY: soft reboot\\r\\n`, then the banner).
- A command goes in by raw-paste (plain raw for hubs without it: raw_paste.py), then the hub answers
  with stdout, `\\x04`, stderr (a traceback), `\\x04`, `>`.

Program output is handed to `on_output` as it arrives. The host's own operations are host calls
(host_call.py): a call with data and a fresh tag, answered by one frame carrying that tag, which is
parsed and never shown as program output. Files travel through host calls too (file_transfer.py). Every wait
has a timeout and a `LinkTimeout` that names what was awaited.
"""

from __future__ import annotations

import asyncio
import zlib
from collections import Counter
from collections.abc import Awaitable, Callable, Sequence
from dataclasses import dataclass, field
from typing import Any

from openbricks.host_protocol import READ_FILE_MAX_BYTES
from openbricks_server.link import file_transfer
from openbricks_server.link.base import Link
from openbricks_server.link.errors import HubException, LinkDropped, LinkError, LinkTimeout, ProtocolError
from openbricks_server.link.host_call import CallOutput, Command, HubInfo, command, single_result
from openbricks_server.link.raw_paste import RAW_BANNER, CommandInput
from openbricks_server.logview import program_lines

CTRL_A, CTRL_B, CTRL_C, CTRL_D = b"\x01", b"\x02", b"\x03", b"\x04"
SOFT_REBOOT = b"soft reboot\r\n"

DEFAULT_TIMEOUT_S = 10.0
ENTER_RETRY_S = 1.0  # a booting hub can miss the first Ctrl-C / Ctrl-A: they are sent again this often
QUIET_S = 0.3  # silence that means a hub has answered every request sent so far
DEFAULT_RUN_TIMEOUT_S = 600.0


@dataclass
class ExecResult:
    """What one command printed: stdout (minus host-call result lines) and stderr (a traceback)."""

    stdout: bytes
    stderr: bytes
    results: list[dict] = field(default_factory=list)
    #: (bytes, crc32) of the output between a program frame and its result frame (run).
    program: tuple[int, int] = (0, 0)


@dataclass(frozen=True)
class LinkEvent:
    """A change of the link during a long command: "dropped" (with the reason) or "reconnected"."""

    kind: str
    hub: str
    detail: str = ""


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
        self.input = CommandInput(link, use_raw_paste=use_raw_paste, send_ahead=send_ahead)
        self._prompt_pending = False
        self._sending = False  # a command is on its way to the hub
        self._interrupt_due = False  # a Ctrl-C waits for the command to be sent
        #: The last `info()` answer, which later choices (compression) go by.
        self.info_cache: HubInfo | None = None

    @property
    def paste_window(self) -> int | None:
        """Bytes per raw-paste flow-control window, as the hub granted it (None until the first paste)."""
        return self.input.window

    @property
    def send_ahead(self) -> bool:
        """Send a command's first two windows along with its paste request (see exec_many)."""
        return self.input.send_ahead

    @send_ahead.setter
    def send_ahead(self, value: bool) -> None:
        self.input.send_ahead = value

    # -- session --------------------------------------------------------------------------------

    async def enter(
        self, *, soft_reset: bool = False, timeout_s: float | None = None, retry_s: float = ENTER_RETRY_S
    ) -> None:
        """Stop whatever runs and enter the raw REPL, from any state (friendly REPL, raw, mid-paste,
        a program running). A hub still booting may miss the request: it is repeated every
        `retry_s` until the banner comes or `timeout_s` runs out."""
        timeout_s = self.timeout_s if timeout_s is None else timeout_s
        self._interrupt_due = False  # entering interrupts whatever runs anyway
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
        """Ctrl-C: raises KeyboardInterrupt in what runs on the hub (its output still follows).

        While a command is still being sent, the Ctrl-C waits until the hub has all of it: during
        a raw-paste it would end the paste, and the rest of the command would land on the raw REPL's
        line and run after all (during plain raw it would clear the line, and the Ctrl-D that
        follows would soft-reset the hub).
        """
        if self._sending:
            self._interrupt_due = True
            return
        await self.link.write(CTRL_C)

    async def _sent(self) -> None:
        """The hub has the whole command: deliver a Ctrl-C asked for while it was being sent."""
        self._sending = False
        if self._interrupt_due:
            self._interrupt_due = False
            await self.link.write(CTRL_C)

    async def _await_prompt(self, timeout_s: float) -> None:
        if self._prompt_pending:
            await self.link.read_until(b">", "the raw REPL prompt", timeout_s)
            self._prompt_pending = False

    # -- executing code -------------------------------------------------------------------------

    async def exec(
        self,
        source: str | bytes | Command,
        *,
        on_output: Callable[[bytes], None] | None = None,
        timeout_s: float | None = None,
    ) -> ExecResult:
        """Run `source` on the hub; raises HubException with the hub's traceback if it raised."""
        result = (await self.exec_many([source], on_output=on_output, timeout_s=timeout_s))[0]
        return result

    async def exec_many(
        self,
        sources: Sequence[str | bytes | Command],
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
        commands = [s if isinstance(s, Command) else Command(s) for s in sources]
        blobs = [c.source.encode() if isinstance(c.source, str) else bytes(c.source) for c in commands]
        results = []
        requested = False  # the current command's paste request went out with the previous end
        early = 0  # bytes of the current command sent along with its request
        for index, blob in enumerate(blobs):
            await self._await_prompt(timeout_s)
            self._sending = True
            try:
                if not requested and self.input.raw_paste:
                    early = await self.input.request(blob, timeout_s)
                    requested = True
                window = await self.input.read_grant(timeout_s, early) if requested else None
                if window is None:
                    await self.input.send_plain_raw(blob, timeout_s)
                    requested, early = False, 0
                else:
                    following = blobs[index + 1] if index + 1 < len(blobs) else None
                    requested, early = await self.input.send(blob, window, early, following, timeout_s)
            finally:
                self._sending = False
            await self._sent()
            result = await self._follow(
                commands[index].tag, on_output, timeout_s, follow_drops, on_link_event
            )
            if result.stderr:
                if requested:
                    await self._cancel_requested_paste(early, timeout_s)
                else:
                    await self._await_prompt(timeout_s)
                error = HubException(
                    self.hub, result.stderr.decode("utf-8", "replace"), result.stdout, result.results
                )
                error.program = result.program
                raise error
            results.append(result)
            if stop_when is not None and stop_when(result) and requested:
                await self._cancel_requested_paste(early, timeout_s)
                break
        await self._await_prompt(timeout_s)
        return results

    async def _cancel_requested_paste(self, early: int, timeout_s: float) -> None:
        """A command was requested behind one that failed: Ctrl-C ends its paste before it compiles."""
        await self._await_prompt(timeout_s)
        window = await self.input.read_grant(timeout_s, early)
        if window is None:
            return
        await self.input.cancel(timeout_s)
        await self._follow(None, None, timeout_s, False, None)
        await self._await_prompt(timeout_s)

    async def _follow(
        self,
        tag: str | None,
        on_output: Callable[[bytes], None] | None,
        timeout_s: float,
        follow_drops: bool,
        on_link_event: Callable[[LinkEvent], None] | None,
    ) -> ExecResult:
        output = CallOutput(tag, on_output)

        async def read_output(remaining: float) -> None:
            while not output.ended:
                rest = output.feed(await self.link.read_some("the command's output", remaining))
                if rest is not None:
                    self.link.unread(rest)

        stderr = bytearray()

        async def read_errors(remaining: float) -> None:
            await self.link.read_until(CTRL_D, "the command's error output", remaining, on_data=stderr.extend)

        await self._read_resilient(
            "the command's output", timeout_s, read_output, follow_drops, on_link_event
        )
        await self._read_resilient(
            "the command's error output", timeout_s, read_errors, follow_drops, on_link_event
        )
        self._prompt_pending = True
        return ExecResult(
            bytes(output.output), bytes(stderr), output.results, (output.program_bytes, output.program_crc32)
        )

    async def _read_resilient(
        self,
        what: str,
        timeout_s: float,
        read: Callable[[float], Awaitable[None]],
        follow_drops: bool,
        on_link_event: Callable[[LinkEvent], None] | None,
    ) -> None:
        """`read(remaining_s)` to its end within `timeout_s`, across drops when `follow_drops`."""
        loop = asyncio.get_running_loop()
        deadline = loop.time() + timeout_s
        while True:
            remaining = deadline - loop.time()
            if remaining <= 0:
                raise LinkTimeout(what, self.hub, timeout_s)
            try:
                await read(remaining)
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
        result = await self.exec(command((name, data)), on_output=on_output, timeout_s=timeout_s)
        return single_result(self.hub, name, result.results, result.stdout)

    async def info(self, *, timeout_s: float | None = None) -> HubInfo:
        """The hub's firmware, runtime and capabilities (kept in `info_cache` for later choices)."""
        self.info_cache = HubInfo.from_result(await self.call("info", timeout_s=timeout_s))
        return self.info_cache

    async def set_rtc(self, epoch_ms: int, *, timeout_s: float | None = None) -> dict:
        return await self.call("set_rtc", epoch_ms=int(epoch_ms), timeout_s=timeout_s)

    async def reset_hub(self, *, timeout_s: float | None = None) -> dict:
        """Restart the hub through its `reset` call and return its confirmation.

        The hub replies and then restarts, so the command never ends the usual way: the reply line
        itself is what is awaited. The session is over afterwards (a USB link drops with the chip).
        """
        timeout_s = self.timeout_s if timeout_s is None else timeout_s
        await self._await_prompt(timeout_s)
        reset = command(("reset", {}))
        await self.input.send_plain_raw(reset.source.encode(), timeout_s)
        output = CallOutput(reset.tag, None)
        while not output.results:
            rest = output.feed(await self.link.read_some("the hub's reply to reset", timeout_s))
            if rest is not None:  # the command ended instead of restarting the hub: it raised
                self.link.unread(rest)
                stderr = await self.link.read_until(CTRL_D, "the error output of reset", timeout_s)
                self._prompt_pending = True
                raise HubException(self.hub, stderr.decode("utf-8", "replace"), bytes(output.output))
        self._prompt_pending = False
        return single_result(self.hub, "reset", output.results, bytes(output.output))

    async def run(
        self,
        path: str | None = None,
        *,
        name: str | None = None,
        on_output: Callable[[bytes], None] | None = None,
        on_link_event: Callable[[LinkEvent], None] | None = None,
        timeout_s: float = DEFAULT_RUN_TIMEOUT_S,
        watch: str | None = None,
    ) -> dict:
        """Run the staged program through the hub's launcher, streaming its output.

        A link that drops meanwhile is reported through `on_link_event` as soon as the transport
        notices, reconnected, and followed on: the hub keeps the program's output while nobody
        listens, so none is lost. A stop (Ctrl-C, the program button) is an outcome, not an error.
        With `watch` (a nonce), the hub announces the run's log key and tags plot() samples with it
        in the output (openbricks.host_calls).
        """
        data = {} if path is None else {"path": path}
        if watch is not None:
            data["watch"] = watch
        if name is not None:
            data["name"] = name  # tracebacks name the program's own file, not the staged one
        await self._await_prompt(self.timeout_s)
        drops = []

        def link_event(event: LinkEvent) -> None:
            drops.append(event)
            if on_link_event is not None:
                on_link_event(event)

        try:
            (result,) = await self.exec_many(
                [command(("run", data))],
                on_output=on_output,
                timeout_s=timeout_s,
                follow_drops=True,
                on_link_event=link_event,
            )
            shown, program, reply = (
                result.stdout,
                result.program,
                single_result(self.hub, "run", result.results, result.stdout),
            )
        except HubException as exc:
            # A stopped run prints its result, then lets KeyboardInterrupt through.
            if not (exc.results and "KeyboardInterrupt" in exc.traceback):
                raise
            shown, program = exc.stdout, getattr(exc, "program", (0, 0))
            reply = single_result(self.hub, "run", exc.results, exc.stdout)
        return await self._check_output(reply, shown, program, bool(drops))

    async def _check_output(self, reply: dict, shown: bytes, program: tuple[int, int], dropped: bool) -> dict:
        """The run's reply, with `damaged_lines` when what arrived does not add up with what the hub
        says its program printed (a damaged link, bytes lost in a drop): the program's lines from
        the hub's run log that did not arrive intact. `unverified` says why they could not be read."""
        printed = (reply.get("printed_bytes"), reply.get("printed_crc32"))
        if reply.get("run") is None or printed[0] is None or (not dropped and tuple(program) == printed):
            return reply
        try:
            text, offset = "", 0
            while offset is not None:
                page, offset = await self.read_run_page(reply["run"], offset)
                text += page
        except LinkError as exc:
            return dict(reply, unverified=str(exc))
        arrived = Counter(shown.decode("utf-8", "replace").replace("\r\n", "\n").split("\n"))
        damaged = []
        for line in program_lines(text):
            if arrived[line] > 0:
                arrived[line] -= 1
            else:
                damaged.append(line)
        return dict(reply, damaged_lines=damaged)

    async def read_run_page(self, index: int, offset: int, *, timeout_s: float | None = None):
        """One slice of run `index`'s log from byte `offset`: (text, next offset or None). A reply
        that is not the slice asked for (damaged on the way) is a ProtocolError, never a KeyError."""
        reply = await self.call("read_run", index=index, offset=offset, timeout_s=timeout_s)
        text, following = reply.get("text"), reply.get("next_offset", -1)
        if (
            reply.get("index") != index
            or reply.get("offset") != offset
            or not isinstance(text, str)
            or not (following is None or (isinstance(following, int) and following > offset))
            or zlib.crc32(text.encode("utf-8", "surrogatepass")) != reply.get("crc32")
        ):
            raise ProtocolError(
                f"{self.hub} answered {str(reply)[:80]!r} for run {index}'s log at byte {offset}: "
                "the reply was damaged on the way; read the log again"
            )
        return text, following

    # -- files ----------------------------------------------------------------------------------

    async def put(
        self,
        path: str,
        data: bytes,
        *,
        compress: bool | None = None,
        call_payload_chars: int = file_transfer.DEFAULT_CALL_PAYLOAD_CHARS,
        timeout_s: float | None = None,
    ) -> dict:
        """Store `data` at `path` on the hub atomically (verified size and crc32 before the rename).

        On the wire: zlib (2 KB window) when the hub has `deflate` and it saves bytes, then base64;
        one `stage` call when the text fits `call_payload_chars`, else `stage_begin` + first chunk,
        middle chunks, last chunk + `stage_end`, pipelined. Upload speed is min(link, 2 windows per
        round trip): with the stock 128-byte window a BLE link at 7.5 ms gives ~17 KB/s, with 2 KB
        windows the link itself is the limit (benchmarks/link_upload.py measures both).

        `compress=None` compresses when `info()` said the hub can inflate (call `info()` first).
        """
        return await file_transfer.put(
            self, path, data, compress=compress, call_payload_chars=call_payload_chars, timeout_s=timeout_s
        )

    async def get(
        self, path: str, *, block_bytes: int = READ_FILE_MAX_BYTES, timeout_s: float | None = None
    ) -> bytes:
        """Read file `path` from the hub through its `read_file` call, every slice checked by size and
        crc32; the slices after the first are pipelined. A missing file raises HubCallError naming it."""
        return await file_transfer.get(self, path, block_bytes=block_bytes, timeout_s=timeout_s)
