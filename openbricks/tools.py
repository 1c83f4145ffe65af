"""Small user-facing utilities mirroring `pybricks.tools`: wait() and StopWatch."""

import time

from openbricks import estop

# A long wait is sliced so that a stop press ends it within one slice even on a hub whose firmware
# cannot inject KeyboardInterrupt (the e-stop latch is checked between slices).
_WAIT_SLICE_MS = 20


def wait(ms):
    """Pause the program for `ms` milliseconds (negative or zero returns at once).

    Raises EStopError as soon as the stop button engages the e-stop.
    """
    estop.check("wait()")
    if ms <= 0:
        return
    deadline = time.ticks_add(time.ticks_ms(), int(ms))
    while True:
        left = time.ticks_diff(deadline, time.ticks_ms())
        if left <= 0:
            return
        time.sleep_ms(left if left < _WAIT_SLICE_MS else _WAIT_SLICE_MS)
        estop.check("wait()")


class StopWatch:
    """Elapsed time in milliseconds, counting from construction; can be paused and resumed."""

    def __init__(self):
        self._paused = False
        self.reset()

    def time(self):
        """Milliseconds counted so far (frozen while paused)."""
        if self._paused:
            return self._elapsed_ms
        return self._elapsed_ms + time.ticks_diff(time.ticks_ms(), self._started_ms)

    def reset(self):
        """Count from zero again; a paused watch stays paused at zero."""
        self._elapsed_ms = 0
        self._started_ms = time.ticks_ms()

    def pause(self):
        if not self._paused:
            self._elapsed_ms += time.ticks_diff(time.ticks_ms(), self._started_ms)
            self._paused = True

    def resume(self):
        if self._paused:
            self._started_ms = time.ticks_ms()
            self._paused = False
