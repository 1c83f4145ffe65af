"""The simulator's clock: simulated time for the user program, with the physics following it.

A hub program sees time through MicroPython's `time.sleep_ms()`/`ticks_ms()`
and `machine.Timer` callbacks. In the simulator that time is the physics
clock: sleeping n ms advances the physics n ms, and Python timers (the
launcher's log pump, a button watcher) fire at their due times on the way.
The physics advances in whole milliseconds; the clock keeps microseconds, so
short sleeps and bus transactions add up exactly.

Between two Python timer due times the physics runs as one native
`mj_step(nstep=n)` call (Physics.step), with the controllers ticked inside it.
Python timers therefore cost one call each, and a program that sleeps 10 s
with no timers pending costs one call for the whole 10 s.

The clock itself never waits: headless runs go as fast as the CPU allows,
and a paced run (real time, twice as fast, paused by a viewer) has a Pacer
(pacing.py), a timer on this clock that holds the program back.

Code that only spins on the clock (`while ticks_diff(...) < 0: pass`) must
still let time pass, as it does on a hub where every call takes CPU time:
each ticks_*() call costs CPU_US_PER_TICKS_CALL of simulated time.
"""

import heapq
import threading
import time

# A ticks_*() call on an ESP32-S3 takes a few microseconds of interpreter time.
CPU_US_PER_TICKS_CALL = 2


class SimTimeLimit(BaseException):
    """The run reached its simulated-time limit. A BaseException, so `except Exception` in a program cannot
    swallow it."""


class SimStopped(BaseException):
    """stop() was requested from outside (a Ctrl-C from the host, a stopped job)."""


class _Scheduled:
    """A Python timer in the queue; cancel() is O(1) (the heap drops cancelled entries lazily)."""

    __slots__ = ("callback", "due_us", "period_us", "cancelled")

    def __init__(self, callback, due_us, period_us):
        self.callback = callback
        self.due_us = due_us
        self.period_us = period_us
        self.cancelled = False

    def cancel(self):
        self.cancelled = True


class SimClock:
    """Simulated time in microseconds, driving `physics.step(n_ms)`.

    physics needs `now_ms` (steps run so far) and `step(n)`; limit_ms ends the
    run with SimTimeLimit.
    """

    def __init__(self, physics, limit_ms=None, epoch_ms=None):
        self._physics = physics
        self._now_us = physics.now_ms * 1000
        self._queue = []  # heap of (due_us, sequence, _Scheduled)
        self._sequence = 0
        self._firing = False
        self._stepping = False  # inside physics.step(): the controllers' tick is running
        self.limit_ms = limit_ms
        self._stop = threading.Event()
        epoch_ms = time.time_ns() // 1_000_000 if epoch_ms is None else epoch_ms
        self._epoch_base_us = int(epoch_ms) * 1000 - self._now_us

    # --- reading -----------------------------------------------------------------------------

    def now_us(self) -> int:
        return self._now_us

    def now_ms(self) -> int:
        return self._now_us // 1000

    def epoch_us(self) -> int:
        """Unix epoch microseconds at the current simulated instant (what the hub's RTC reads)."""
        return self._epoch_base_us + self._now_us

    def set_epoch_ms(self, epoch_ms) -> None:
        """Set the RTC: the wall clock reads epoch_ms now (simulated time itself does not jump)."""
        self._epoch_base_us = int(epoch_ms) * 1000 - self._now_us

    def charge_cpu_us(self, us: int) -> None:
        """Let a little time pass for work done on the CPU (a ticks_*() call, a bus transfer).

        Inside the physics step (a controller's Python heading source reading an I2C IMU on the
        1 kHz tick) time is already passing, one tick at a time: the transfer is part of that
        tick, as on the hub, and must not step the physics from within itself."""
        if self._stepping:
            return
        self.advance_us(us)

    # --- timers -------------------------------------------------------------------------------

    def schedule(self, callback, delay_us: int, period_us: int = 0) -> _Scheduled:
        """Call callback() after delay_us, then every period_us if > 0. Returns a handle with cancel()."""
        entry = _Scheduled(callback, self._now_us + max(0, int(delay_us)), int(period_us))
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

    # --- advancing ------------------------------------------------------------------------------

    def request_stop(self) -> None:
        """Make the program's next sleep (or bus transfer) raise SimStopped. Safe from any thread."""
        self._stop.set()

    def advance_us(self, us: int) -> None:
        """Let us microseconds of simulated time pass, firing due timers and running the physics."""
        if self._stop.is_set():
            self._stop.clear()
            raise SimStopped("the run was stopped")
        target = self._now_us + max(0, int(us))
        if self._firing:
            # A timer callback that sleeps moves time on, but timers do not nest (as on the hub,
            # where one soft callback runs at a time).
            self._run_physics_to(target)
            self._now_us = target
            return
        while True:
            due = self._next_due()
            if due is None or due > target:
                break
            self._run_physics_to(due)
            self._now_us = max(self._now_us, due)
            _, _, entry = heapq.heappop(self._queue)
            if entry.period_us > 0:
                entry.due_us += entry.period_us
                self._push(entry)
            else:
                entry.cancelled = True
            self._firing = True
            try:
                entry.callback()
            finally:
                self._firing = False
        self._run_physics_to(target)
        self._now_us = max(self._now_us, target)  # a timer callback's own charges may have gone past

    def _run_physics_to(self, t_us: int) -> None:
        physics = self._physics
        target_ms = t_us // 1000
        if self.limit_ms is not None and target_ms > self.limit_ms:
            self._step(self.limit_ms - physics.now_ms)
            self._now_us = max(self._now_us, self.limit_ms * 1000)
            raise SimTimeLimit(f"the run reached its simulated time limit of {self.limit_ms} ms")
        self._step(target_ms - physics.now_ms)

    def _step(self, n_ms: int) -> None:
        if n_ms <= 0:
            return
        self._stepping = True
        try:
            self._physics.step(n_ms)
        finally:
            self._stepping = False
