"""Small user-facing utilities mirroring `pybricks.tools`: wait(), StopWatch, and plot() for live graphs."""

import json
import time

from openbricks import estop
from openbricks.host_protocol import FRAME_PREFIX

PLOT_NAME_MAX = 40
# The nonce of the host watching this run (the console daemon hands one over with `run`/`idle`), or
# None: a plot line carries it, so output a program prints itself never turns into a sample.
_plot_tag = [None]

# A long wait is sliced so that a stop press ends it within one slice even on a hub whose firmware
# cannot inject KeyboardInterrupt (the e-stop latch is checked between slices).
_WAIT_SLICE_MS = 20


def wait(milliseconds):
    """Pause the program for `milliseconds` (negative or zero returns at once), as Pybricks' wait().

    Raises EStopError as soon as the stop button engages the e-stop.
    """
    estop.check("wait()")
    if milliseconds <= 0:
        return
    deadline = time.ticks_add(time.ticks_ms(), int(milliseconds))
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
        """Stop counting; time() keeps returning the elapsed ms until resume()."""
        if not self._paused:
            self._elapsed_ms += time.ticks_diff(time.ticks_ms(), self._started_ms)
            self._paused = True

    def resume(self):
        """Count on from where pause() stopped."""
        if self._paused:
            self._started_ms = time.ticks_ms()
            self._paused = False


def _plot_value(value):
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise TypeError("plot() value must be a number, not %s" % type(value).__name__)
    if isinstance(value, float) and (value != value or value in (float("inf"), float("-inf"))):
        raise ValueError("plot() value must be finite, got %r" % (value,))
    return value


def plot(name, value):
    """Send one sample of the series `name` to the console's live graph (and the run's history).

    With the console watching, the line is a tagged frame it turns into a telemetry sample; run
    without it (`openbricks run` straight to the hub), it prints as `plot: name = value`. Plain
    print() output is never taken for a sample.
    """
    if not isinstance(name, str) or not name or len(name) > PLOT_NAME_MAX:
        raise ValueError("plot() name must be 1..%d characters of text, got %r" % (PLOT_NAME_MAX, name))
    for char in name:
        if ord(char) < 32:
            raise ValueError("plot() name %r holds a control character" % (name,))
    value = _plot_value(value)
    tag = _plot_tag[0]
    if tag is None:
        print("plot: %s = %s" % (name, json.dumps(value)))
    else:
        print(FRAME_PREFIX + tag + " plot " + json.dumps({"name": name, "value": value}))
