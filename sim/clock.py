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

Most advances have nothing due on the way: a move's 10 ms poll, a ticks_ms()
read. Those go straight to the native controller's step, skipping the timer
queue and the layers between the clock and the physics, because that Python
is most of what a waiting program costs beside the physics itself.

The clock itself never waits: headless runs go as fast as the CPU allows,
and a paced run (real time, twice as fast, paused by a viewer) has a Pacer
(pacing.py), a timer on this clock that holds the program back.

Code that only spins on the clock (`while ticks_diff(...) < 0: pass`) must
still let time pass, as it does on a hub where every call takes CPU time:
each ticks_*() call costs CPU_US_PER_TICKS_CALL (shim/mptime.py) of simulated time.
"""

import time

from .shim.virtual_clock import VirtualClock


class SimTimeLimit(BaseException):
    """The run reached its simulated-time limit. A BaseException, so `except Exception` in a program cannot
    swallow it."""


class SimStopped(BaseException):
    """stop() was requested from outside (a Ctrl-C from the host, a stopped job)."""


class SimClock(VirtualClock):
    """The hub's virtual clock (shim/virtual_clock.py) driving `physics.step(n_ms)` as it advances.

    physics needs `now_ms` (steps run so far) and `step(n)`; limit_ms ends the
    run with SimTimeLimit.
    """

    def __init__(self, physics, limit_ms=None, epoch_ms=None):
        epoch_ms = time.time_ns() // 1_000_000 if epoch_ms is None else epoch_ms
        super().__init__(physics.now_ms * 1000, epoch_ms)
        self._physics = physics
        self._stepping = False  # inside physics.step(): the controllers' tick is running
        self.limit_ms = limit_ms
        self._stop_requested = False  # a bool, not an Event: read on every advance, set from any thread
        self._controller = None  # the physics' native controller, once built (the fast path's step)
        # The Python-time charge (python_cost.py) while a program runs: the clock's own work is the
        # hub's, so counting stops while time advances and starts again for each timer callback.
        self.python_cost = None

    def charge_cpu_us(self, us: int) -> None:
        """Let a little time pass for work done on the CPU (a ticks_*() call, a bus transfer).

        Inside the physics step (a controller's Python heading source reading an I2C IMU on the
        1 kHz tick) time is already passing, one tick at a time: the transfer is part of that
        tick, as on the hub, and must not step the physics from within itself."""
        if self._stepping:
            return
        target_us = self._now_us + max(0, int(us))
        queue = self._queue
        if (
            target_us // 1000 == self._now_us // 1000  # the physics is where it must be already
            and not self._stop_requested
            and not self._advancing
            and not self._next_time
            and (not queue or queue[0][0] > target_us)
        ):
            self._now_us = target_us  # most charges (a ticks_*() read): nothing else to do
            return
        self.advance_us(us)

    def request_stop(self) -> None:
        """Make the program's next sleep (or bus transfer) raise SimStopped. Safe from any thread."""
        self._stop_requested = True

    def follow(self, controller) -> None:
        """Step `controller` (the built physics' openbricks_mjcontrol.Controller) directly when nothing
        else is due: it is what physics.step() would call."""
        self._controller = controller

    def advance_us(self, us: int) -> None:
        """Let us microseconds of simulated time pass, firing due timers and running the physics."""
        if self._stop_requested:
            self._stop_requested = False
            raise SimStopped("the run was stopped")
        # The clock's own work is the hub's: no charge for it, and no profile hook slowing it down.
        cost = self.python_cost
        counting = cost is not None and cost.counting
        if counting:
            cost.pause()
        try:
            controller = self._controller
            if controller is not None and not self._advancing and not self._next_time:
                target_us = self._now_us + max(0, int(us))
                queue = self._queue
                nothing_due = not queue or queue[0][0] > target_us
                limit_ms = self.limit_ms
                if nothing_due and (limit_ms is None or target_us < limit_ms * 1000):
                    n_ms = target_us // 1000 - controller.now_ms
                    if n_ms > 0:
                        self._stepping = True
                        try:
                            controller.step(n_ms)
                        finally:
                            self._stepping = False
                    self._now_us = target_us
                    return
            super().advance_us(us)
        finally:
            if counting:
                cost.resume()

    def schedule(self, callback, delay_us, period_us=0):
        """VirtualClock.schedule(); the callback is the program's or the runtime's code, so it counts."""

        def counted():
            cost = self.python_cost
            if cost is None or cost.counting:
                callback()
                return
            cost.resume()
            try:
                callback()
            finally:
                cost.pause()

        return super().schedule(counted, delay_us, period_us)

    def _run_to(self, t_us: int) -> None:
        """The physics follows the clock: it steps up to t_us before time may read it."""
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
