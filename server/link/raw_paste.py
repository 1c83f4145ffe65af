"""Getting a command's bytes into the hub: raw-paste with its flow control, plain raw as the fallback.

Raw-paste, as the hub's `pyexec.c` implements it: `\\x05A\\x01` -> `R\\x01`, the window W (16-bit
little endian) and `\\x01`. The host may have W bytes in flight per `\\x01` received (the first two
arrive together: 2W to start), so the hub never buffers more than 2W. Ctrl-D ends the data and the
hub acknowledges with `\\x04`; it may also end the paste early with its own `\\x04` (a compile-time
failure it will report). `R\\x00` means the hub has raw-paste switched off; a runtime without
raw-paste takes the request as text plus a Ctrl-A and re-prints the raw banner.

Plain raw (source, Ctrl-D -> `OK`) has no flow control at all: it is only for hubs that refuse
raw-paste, and is paced in chunks smaller than the stock hub's stdin ring.

Throughput is window / round trip: two windows may be in flight, each refilled by one `\\x01`.
"""

from __future__ import annotations

import asyncio
import struct

from openbricks_server.link.base import Link
from openbricks_server.link.errors import LinkDropped, ProtocolError

CTRL_A, CTRL_C, CTRL_D = b"\x01", b"\x03", b"\x04"
RAW_BANNER = b"raw REPL; CTRL-B to exit\r\n"
PASTE_ENTER = b"\x05A\x01"
PLAIN_RAW_CHUNK_BYTES = 256  # the stock hub's stdin ring holds 260: no flow control without raw-paste
PLAIN_RAW_PACE_S = 0.01


class CommandInput:
    """Sends commands to one hub's raw REPL, within the window the hub granted.

    Remembers per session whether the hub speaks raw-paste and which window it granted. With
    `send_ahead`, once the window is known, a command's first two windows go out right behind its
    paste request: a hub's stdin ring holds them (it is sized for two windows plus a few bytes, and
    is empty then), but a hub model that only credits bytes sent after the grant was seen counts them
    as overrun, so it is off by default.
    """

    def __init__(self, link: Link, *, use_raw_paste: bool = True, send_ahead: bool = False):
        self.link = link
        self.hub = link.hub
        #: Bytes per raw-paste flow-control window, as the hub granted it (None until the first paste).
        self.window: int | None = None
        #: False once the hub showed it only speaks plain raw.
        self.raw_paste = use_raw_paste
        self.send_ahead = send_ahead

    def early_length(self, blob: bytes) -> int:
        """How much of a command may go out with its paste request: the 2 windows the grant will
        give, once a grant in this session told the window (0 before, or with `send_ahead` off)."""
        if not self.send_ahead or self.window is None:
            return 0
        return min(len(blob), 2 * self.window)

    async def request(self, blob: bytes, timeout_s: float) -> int:
        """Ask for a raw-paste for `blob`; returns how many of its bytes went out with the request."""
        early = self.early_length(blob)
        await self.link.write(PASTE_ENTER + blob[:early], timeout_s)
        return early

    async def read_grant(self, timeout_s: float, early: int = 0) -> int | None:
        """The hub's answer to a paste request: the window size, or None if it only speaks plain raw
        (from then on this session sends plain raw)."""
        head = await self.link.read_exactly(2, "the raw-paste reply", timeout_s)
        if head == b"R\x01":
            raw = await self.link.read_exactly(2, "the raw-paste window", timeout_s)
            (window,) = struct.unpack("<H", raw)
            if window == 0:
                raise ProtocolError(f"{self.hub} granted a raw-paste window of 0 bytes")
            self.window = window
            return window
        self.raw_paste = False
        if head == b"R\x00":
            await self.link.read_until(b">", "the raw REPL prompt after a refused raw-paste", timeout_s)
        else:
            await self.link.read_until(RAW_BANNER + b">", "the raw REPL banner", timeout_s)
        if early:
            await self.link.write(CTRL_C, timeout_s)  # the early bytes landed on the raw line: clear it
        return None

    async def send(
        self, data: bytes, window: int, early: int, following: bytes | None, timeout_s: float
    ) -> tuple[bool, int]:
        """Stream the rest of `data` within the hub's windows and end it, requesting the `following`
        command's paste (with its early bytes) in the same write, so its grant comes back with this
        command's answer instead of costing a round trip of its own. Returns (next requested, its
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
            next_early = self.early_length(following)
            tail += PASTE_ENTER + following[:next_early]
        await self.link.write(tail, timeout_s)
        await self.read_ack(timeout_s)
        return following is not None, next_early

    async def cancel(self, timeout_s: float) -> None:
        """Ctrl-C ends a paste the hub granted before any of it compiles; the hub answers as for a
        command interrupted by KeyboardInterrupt."""
        await self.link.write(CTRL_C, timeout_s)
        await self.read_ack(timeout_s)

    async def read_ack(self, timeout_s: float) -> None:
        ack = await self.link.read_until(CTRL_D, "the end-of-paste acknowledgement", timeout_s)
        if ack.strip(CTRL_A):
            raise ProtocolError(
                f"{self.hub} sent {ack[:40]!r} during a raw-paste upload instead of flow control"
            )

    async def send_plain_raw(self, data: bytes, timeout_s: float) -> None:
        """A whole command without flow control, paced so the hub's stdin ring keeps up."""
        for start in range(0, len(data), PLAIN_RAW_CHUNK_BYTES):
            await self.link.write(data[start : start + PLAIN_RAW_CHUNK_BYTES], timeout_s)
            await asyncio.sleep(PLAIN_RAW_PACE_S)
        await self.link.write(CTRL_D, timeout_s)
        ok = await self.link.read_exactly(2, "the raw REPL's OK", timeout_s)
        if ok != b"OK":
            raise ProtocolError(f"{self.hub} answered {ok!r} instead of OK to a raw REPL command")

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
