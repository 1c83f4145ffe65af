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
each ticks_*() call costs CPU_US_PER_TICKS_CALL (shim/mptime.py) of simulated time.
"""

import threading
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
        self._stop = threading.Event()
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
        self.advance_us(us)

    def request_stop(self) -> None:
        """Make the program's next sleep (or bus transfer) raise SimStopped. Safe from any thread."""
        self._stop.set()

    def advance_us(self, us: int) -> None:
        """Let us microseconds of simulated time pass, firing due timers and running the physics."""
        if self._stop.is_set():
            self._stop.clear()
            raise SimStopped("the run was stopped")
        cost = self.python_cost
        if cost is None or not cost.counting:
            super().advance_us(us)
            return
        cost.pause()
        try:
            super().advance_us(us)
        finally:
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
