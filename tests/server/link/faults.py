"""A `Link` that injects seeded faults into the bytes between a host and a hub, for the fault harness
(tests/server/link/fault_harness.py, benchmarks/fault_injection.py) and any test that needs a bad link.

`FaultyLink(inner, faults)` wraps any link (BLE through the emulated radio, a virtual hub's pty, a
loopback) and changes the byte streams at the offsets its `Fault`s name, counted per direction
from the first byte of the session:

- drop: `size` bytes vanish; truncate: the rest of the chunk they fall in vanishes;
- duplicate: `size` bytes arrive twice; reorder: two neighbouring pieces within a `size`-byte
  window swap places;
- delay: from that byte on, everything in that direction arrives `delay_s` later (order kept);
- disconnect: the link goes down there (bytes after it are lost); `reconnect()` brings it back.

Everything is decided by the faults given, so a seed reproduces a run exactly (timing aside).
"""

from __future__ import annotations

import asyncio
import random
from collections import deque
from collections.abc import Sequence
from dataclasses import dataclass

from openbricks_server.link.base import Link

KINDS = ("drop", "truncate", "duplicate", "reorder", "delay", "disconnect")
TO_HUB, TO_HOST = "to_hub", "to_host"


@dataclass(frozen=True)
class Fault:
    kind: str
    direction: str
    at_byte: int
    size: int = 1
    delay_s: float = 0.0

    def describe(self) -> str:
        extra = f" {self.delay_s * 1000:.0f} ms" if self.kind == "delay" else f" {self.size} B"
        return f"{self.kind}{extra} {self.direction} at byte {self.at_byte}"


def seeded_faults(seed: int, to_hub_bytes: int, to_host_bytes: int, count: int = 1) -> list[Fault]:
    """`count` faults for `seed`, at offsets spread over a session's usual traffic each way, so every
    phase (entering the raw REPL, pasting, host calls, run streaming, log reads) gets its share."""
    rng = random.Random(seed)
    faults = []
    for _ in range(count):
        kind = rng.choice(KINDS)
        direction = rng.choice((TO_HUB, TO_HOST))
        span = to_hub_bytes if direction == TO_HUB else to_host_bytes
        faults.append(
            Fault(
                kind,
                direction,
                rng.randrange(max(span, 1)),
                size=rng.randint(1, 64),
                delay_s=rng.uniform(0.01, 0.5),
            )
        )
    return faults


class FaultyLink(Link):
    """`inner` with `faults` applied; `fired` lists the faults that took effect, in order."""

    def __init__(self, inner: Link, faults: Sequence[Fault]):
        super().__init__(
            inner.hub, connect_timeout_s=inner.connect_timeout_s, write_timeout_s=inner.write_timeout_s
        )
        self.inner = inner
        self.can_reconnect = inner.can_reconnect
        self.faults = sorted(faults, key=lambda f: f.at_byte)
        self.fired: list[Fault] = []
        self._seen = {TO_HUB: 0, TO_HOST: 0}
        self._hold_until = {TO_HUB: 0.0, TO_HOST: 0.0}
        self._down = False
        self._incoming: deque[tuple[float, bytes]] = deque()  # hub bytes on their way, in order
        self._timer: asyncio.TimerHandle | None = None
        # The inner transport reports to us instead of to its own buffer.
        inner._received = self._from_hub
        inner._dropped = self._inner_dropped

    def _describe(self) -> str:
        return f"faulty {self.inner._describe()}"

    async def _open(self) -> None:
        if self.inner.is_open:
            await self.inner.close()
        await self.inner.connect()
        self._down = False

    async def _close(self) -> None:
        await self.inner.close()

    def _inner_dropped(self, reason: str) -> None:
        self._dropped(reason)

    # -- the faults ---------------------------------------------------------------------------------

    def _apply(self, direction: str, data: bytes) -> tuple[list[tuple[float, bytes]], bool]:
        """The pieces to deliver (each with its delay) and whether the link goes down after them."""
        start = self._seen[direction]
        self._seen[direction] += len(data)
        out = bytearray(data)
        delay_at = None
        delay_s = 0.0
        cut = None
        for fault in self.faults:
            if fault.direction != direction or not start <= fault.at_byte < start + len(data):
                continue
            k = fault.at_byte - start
            self.fired.append(fault)
            if fault.kind == "drop":
                del out[k : k + fault.size]
            elif fault.kind == "truncate":
                del out[k:]
            elif fault.kind == "duplicate":
                out[k:k] = out[k : k + fault.size]
            elif fault.kind == "reorder":
                window = out[k : k + fault.size]
                half = max(1, len(window) // 2)
                out[k : k + len(window)] = window[half:] + window[:half]
            elif fault.kind == "delay":
                delay_at, delay_s = k, fault.delay_s
            elif fault.kind == "disconnect":
                cut = k
        if cut is not None:
            del out[cut:]
        pieces = []
        if delay_at is None:
            pieces.append((0.0, bytes(out)))
        else:
            pieces += [(0.0, bytes(out[:delay_at])), (delay_s, bytes(out[delay_at:]))]
        return [(d, p) for d, p in pieces if p], cut is not None

    def _when(self, direction: str, delay_s: float) -> float:
        loop = asyncio.get_running_loop()
        if delay_s:
            self._hold_until[direction] = max(self._hold_until[direction], loop.time()) + delay_s
        return max(loop.time(), self._hold_until[direction])

    async def _send(self, data: bytes) -> None:
        if self._down:
            return  # lost on a link that is down, as writes during a supervision timeout are
        pieces, goes_down = self._apply(TO_HUB, data)
        loop = asyncio.get_running_loop()
        for delay_s, piece in pieces:
            wait = self._when(TO_HUB, delay_s) - loop.time()
            if wait > 0:
                await asyncio.sleep(wait)
            await self.inner.write(piece)
        if goes_down:
            self._go_down()

    def _from_hub(self, data: bytes) -> None:
        if self._down or not data:
            return
        pieces, goes_down = self._apply(TO_HOST, data)
        for delay_s, piece in pieces:
            self._incoming.append((self._when(TO_HOST, delay_s), piece))
        self._schedule_delivery()
        if goes_down:
            self._go_down()

    def _schedule_delivery(self) -> None:
        # One timer at a time, for the head of the queue: timers due at the same moment are not
        # run in the order they were made, and the bytes must keep theirs.
        if self._incoming and self._timer is None:
            loop = asyncio.get_running_loop()
            self._timer = loop.call_at(self._incoming[0][0], self._deliver)

    def _deliver(self) -> None:
        self._timer = None
        now = asyncio.get_running_loop().time()
        while self._incoming and self._incoming[0][0] <= now:
            _when, data = self._incoming.popleft()
            if not self._down:
                self._received(data)
        self._schedule_delivery()

    def _go_down(self) -> None:
        self._down = True
        self._incoming.clear()
        self._dropped("injected disconnect")
        asyncio.get_running_loop().create_task(self.inner.close())
