"""The event stream: every change the daemon sees, numbered once and fanned out to every client.

Each published event gets the next `seq` (strictly increasing for the daemon's lifetime and, because a
new lifetime starts after the last stored number, across restarts too) and is serialised once. Clients
are `Subscriber`s with a bounded queue. Publishing never waits for a client: a client whose queue is
full stops receiving live events, drains what it has, is told `resync`, and catches up from the memory
ring or, past it, from the store, at its own pace, then goes live again. Hubs and the other clients are
never slowed by it.

Control messages addressed to one client (`hello`, `gap`, `resync`, `reply`) have `"seq": null`: they
are not part of the numbered stream, so a client's "last seq" only ever counts real events.
A `gap` says which sequence numbers the daemon cannot send and why; nothing is skipped silently.
"""

from __future__ import annotations

import asyncio
import json
from collections import deque
from collections.abc import Awaitable, Callable
from itertools import islice

from openbricks_server.daemon.store import Store, now_ms

CATCH_UP_BATCH = 500  # sequence numbers fetched per step while a client catches up
SEND_BATCH = 256  # queued messages handed to the socket per wake-up


def _dumps(envelope: dict) -> str:
    return json.dumps(envelope, separators=(",", ":"), ensure_ascii=False)


def control(type_: str, data: dict) -> str:
    """A message for one client, outside the numbered stream."""
    return _dumps({"seq": None, "type": type_, "hub": None, "run": None, "ts": now_ms(), "data": data})


class Subscriber:
    """One client's view of the stream: a bounded queue of (seq, text), and where it is in the stream."""

    def __init__(self, bus: EventBus, queue_size: int, last_seq: int, behind: bool):
        self.bus = bus
        self.queue: asyncio.Queue[tuple[int, str]] = asyncio.Queue(queue_size)
        self.last_seq = last_seq  # the last numbered event this client was sent
        self.behind = behind  # live events are not queued; the sender catches up from ring/store first
        self.overflowed = False  # behind because the queue filled up (the client is told `resync`)
        self.resyncs = 0

    def offer(self, seq: int, text: str) -> None:
        if self.behind:
            return
        try:
            self.queue.put_nowait((seq, text))
        except asyncio.QueueFull:
            self.behind = self.overflowed = True
            self.resyncs += 1

    async def pump(self, send: Callable[[list[str]], Awaitable[None]], pace_s: float = 0.0) -> None:
        """Send this client its events forever, in order, catching up whenever it is behind. Whatever is
        queued goes out in one `send` call (fewer wake-ups when output is dense). With `pace_s`, a send
        follows the previous one by at least that long, so what arrives meanwhile goes out together: a
        browser pays for every message it is handed, and draws at most once per display frame anyway."""
        loop = asyncio.get_running_loop()
        sent_at = -pace_s
        while True:
            if self.behind and self.queue.empty():
                if self.overflowed:
                    self.overflowed = False
                    resync = {
                        "from_seq": self.last_seq + 1,
                        "to_seq": self.bus.seq,
                        "reason": "fell behind the live stream; catching up from the store",
                    }
                    await send([control("resync", resync)])
                await self._catch_up(send)
                continue
            batch = [await self.queue.get()]
            if pace_s:
                await asyncio.sleep(sent_at + pace_s - loop.time())
            while len(batch) < SEND_BATCH and not self.queue.empty():
                batch.append(self.queue.get_nowait())
            await send([text for _, text in batch])
            sent_at = loop.time()
            self.last_seq = batch[-1][0]

    async def _catch_up(self, send: Callable[[list[str]], Awaitable[None]]) -> None:
        while True:
            batch = self.bus.fetch(self.last_seq, CATCH_UP_BATCH)
            if not batch:
                self.behind = False  # no await since the fetch: nothing was published in between
                return
            await send([text for _, text in batch])
            self.last_seq = batch[-1][0]


class EventBus:
    def __init__(self, store: Store, boot_id: str, first_seq: int, ring_size: int, queue_size: int):
        self.store = store
        self.boot_id = boot_id
        self.first_seq = first_seq
        self.seq = first_seq - 1  # the last number given out
        self.queue_size = queue_size
        self._ring: deque[tuple[int, str]] = deque(maxlen=ring_size)
        self._subscribers: set[Subscriber] = set()
        # Called before reading the store, so what was published but not yet written is written first
        # (the recorder's pending output lines).
        self.before_store_read: Callable[[], None] = lambda: None

    def next_seq(self) -> int:
        self.seq += 1
        return self.seq

    def publish(
        self,
        type_: str,
        data: dict,
        hub: str | None = None,
        run: str | None = None,
        *,
        ts: int | None = None,
        persist: bool = True,
        seq: int | None = None,
    ) -> int:
        """Number, (optionally) store and fan out one event; returns its seq. With `persist=False` the
        caller stores it itself under the returned seq (output lines, telemetry) or it is ephemeral.
        `seq`, from `next_seq()`, publishes under a number taken earlier (the latest one taken)."""
        if seq is None:
            seq = self.next_seq()
        ts = now_ms() if ts is None else ts
        if persist:
            self.store.events.add(seq, type_, hub, run, ts, data)
        text = _dumps({"seq": seq, "type": type_, "hub": hub, "run": run, "ts": ts, "data": data})
        self._ring.append((seq, text))
        for subscriber in self._subscribers:
            subscriber.offer(seq, text)
        return seq

    @property
    def subscribers(self) -> int:
        return len(self._subscribers)

    def subscribe(self, since: int | None = None, boot: str | None = None) -> tuple[Subscriber, list[str]]:
        """A new client, live from now, or replayed from after `since` (its last seq, of lifetime `boot`
        when given). Returns it with the control messages to send it first (hello, maybe a gap)."""
        first: list[str] = []
        after, gap = self._resume_point(since, boot)
        hello = {"boot": self.boot_id, "seq": self.seq, "first_seq": self.first_seq, "resume_from": after}
        first.append(control("hello", hello))
        if gap:
            first.append(control("gap", gap))
        subscriber = Subscriber(self, self.queue_size, last_seq=after, behind=after < self.seq)
        self._subscribers.add(subscriber)
        return subscriber, first

    def unsubscribe(self, subscriber: Subscriber) -> None:
        self._subscribers.discard(subscriber)

    def _resume_point(self, since: int | None, boot: str | None) -> tuple[int, dict | None]:
        if since is None:
            return self.seq, None
        if boot is not None and boot != self.boot_id:
            boot_first = self.store.events.boot_first_seq(boot)
            if boot_first is None:
                return self.seq, {
                    "from_seq": None,
                    "to_seq": self.seq,
                    "reason": "unknown_lifetime",
                    "message": f"this daemon has no record of lifetime {boot}; its events cannot be replayed",
                    "hint": "reload the current state (GET /api/hubs, /api/runs) and follow the live stream",
                }
            # Numbers the client saw after the last stored one of its lifetime were given out again by a
            # later lifetime: replay from the first number of the lifetime that followed it.
            following = self.store.db.query_one(
                "SELECT min(first_seq) FROM boots WHERE first_seq > ?", (boot_first,)
            )[0]
            if following is not None:
                since = min(since, following - 1)
        if since > self.seq:
            return self.seq, {
                "from_seq": None,
                "to_seq": self.seq,
                "reason": "ahead_of_stream",
                "message": f"seq {since} was never given out by this daemon (it is at {self.seq})",
                "hint": "send the boot id from the hello message with since=, or reload the current state",
            }
        return max(since, 0), None

    def fetch(self, after: int, limit: int) -> list[tuple[int, str]]:
        """Up to `limit` sequence numbers' worth of messages after `after`: events from the ring or the
        store, and `gap` messages (numbered with the last missing seq) for what neither has."""
        if after >= self.seq:
            return []
        ring_first = self._ring[0][0] if self._ring else self.seq + 1
        if after + 1 >= ring_first:
            start = after + 1 - ring_first
            return list(islice(self._ring, start, start + limit))
        upto = min(ring_first - 1, after + limit)
        self.before_store_read()
        stored = {e["seq"]: e for e in self.store.events.between(after, upto)}
        out: list[tuple[int, str]] = []
        missing_from = None
        for seq in range(after + 1, upto + 1):
            event = stored.get(seq)
            if event is None:
                if missing_from is None:
                    missing_from = seq
                continue
            if missing_from is not None:
                out.append((seq - 1, self._gap_message(missing_from, seq - 1)))
                missing_from = None
            out.append((seq, _dumps(event)))
        if missing_from is not None:
            out.append((upto, self._gap_message(missing_from, upto)))
        return out

    def _gap_message(self, from_seq: int, to_seq: int) -> str:
        if to_seq < self.first_seq:
            reason, message = "not_saved", "these events were sent before the daemon restarted and not saved"
        else:
            reason, message = "not_kept", "these events were not kept (only hub, run and output events are)"
        return control(
            "gap",
            {
                "from_seq": from_seq,
                "to_seq": to_seq,
                "reason": reason,
                "message": message,
                "hint": "reload the current state (GET /api/hubs, /api/runs/{id}/output) if it matters",
            },
        )
