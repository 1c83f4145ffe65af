"""Time as a simulated hub lives it: microseconds that pass only when the program lets them, with
callbacks due on the way.

A hub program sees time through `time.sleep_ms()`/`ticks_ms()`, `machine.Timer` callbacks and
`micropython.schedule()`. Here all three run on one queue: sleeping n us fires, in order, every
callback that falls due within those n us, then leaves the clock n us later. Nothing runs on its
own, so a test or a simulation decides exactly when time moves.

The simulator's clock (sim/clock.py) is this clock with the physics following it; the runtime's
tests use it as it is. It keeps to MicroPython's language because those tests also run under
MicroPython.
"""

import heapq


class Scheduled:
    """A callback in the queue; cancel() is O(1) (the heap drops cancelled entries lazily)."""

    def __init__(self, callback, due_us, period_us, soon=False):
        self.callback = callback
        self.due_us = due_us
        self.period_us = period_us
        self.soon = soon  # scheduled to run as soon as time moves on
        self.cancelled = False

    def cancel(self):
        self.cancelled = True


class VirtualClock:
    """Simulated time in microseconds, with a wall clock (the RTC) that reads `epoch_ms` at `now_us`."""

    def __init__(self, now_us=0, epoch_ms=0):
        self._now_us = now_us
        self._queue = []  # heap of (due_us, sequence, Scheduled)
        self._sequence = 0
        self._advancing = False
        self._firing_soon = False  # running a callback scheduled to run as soon as possible
        self._next_time = []  # what such a callback scheduled in its turn: it waits for the next advance
        self._epoch_base_us = int(epoch_ms) * 1000 - now_us

    # --- reading ---------------------------------------------------------------------------

    def now_us(self):
        return self._now_us

    def now_ms(self):
        return self._now_us // 1000

    def epoch_us(self):
        """Unix epoch microseconds at the current simulated instant (what the hub's RTC reads)."""
        return self._epoch_base_us + self._now_us

    def set_epoch_ms(self, epoch_ms):
        """Set the RTC: the wall clock reads epoch_ms now (simulated time itself does not jump)."""
        self._epoch_base_us = int(epoch_ms) * 1000 - self._now_us

    def charge_cpu_us(self, us):
        """Let a little time pass for work done on the CPU (a ticks_*() call, a bus transfer)."""
        self.advance_us(us)

    # --- callbacks ---------------------------------------------------------------------------

    def schedule(self, callback, delay_us, period_us=0):
        """Call callback() after delay_us, then every period_us if > 0. Returns a handle with cancel().

        A callback scheduled with no delay runs at the next moment time moves on, never inside this
        call; one scheduled so by such a callback waits for the advance after that, so a callback
        that keeps rescheduling itself cannot hold time still."""
        soon = delay_us <= 0 and period_us <= 0
        entry = Scheduled(callback, self._now_us + max(0, int(delay_us)), int(period_us), soon)
        if soon and self._firing_soon:
            self._next_time.append(entry)
        else:
            self._push(entry)
        return entry

    def _push(self, entry):
        self._sequence += 1
        heapq.heappush(self._queue, (entry.due_us, self._sequence, entry))

    def _next_due(self):
        queue = self._queue
        while queue and queue[0][2].cancelled:
            heapq.heappop(queue)
        return queue[0][0] if queue else None

    # --- advancing -----------------------------------------------------------------------------

    def advance_us(self, us):
        """Let us microseconds pass, firing every callback due on the way at its due time."""
        target = self._now_us + max(0, int(us))
        if self._advancing:
            # A callback that sleeps moves time on, but callbacks do not nest (as on the hub, where
            # one soft callback runs at a time).
            self._run_to(target)
            self._now_us = max(self._now_us, target)
            return
        self._advancing = True
        try:
            for entry in self._next_time:
                entry.due_us = max(entry.due_us, self._now_us)
                self._push(entry)
            self._next_time = []
            while True:
                due = self._next_due()
                if due is None or due > target:
                    break
                self._run_to(due)
                self._now_us = max(self._now_us, due)
                entry = heapq.heappop(self._queue)[2]
                if entry.period_us > 0:
                    entry.due_us += entry.period_us
                    self._push(entry)
                else:
                    entry.cancelled = True
                self._firing_soon = entry.soon
                try:
                    entry.callback()
                finally:
                    self._firing_soon = False
            self._run_to(target)
            self._now_us = max(self._now_us, target)  # a callback's own charges may have gone past
        finally:
            self._advancing = False

    def _run_to(self, t_us):
        """What else must reach t_us before time may read it (the simulator's physics)."""
