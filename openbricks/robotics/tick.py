"""Keeps `motor_process` ticking: the 1 kHz clock every native controller (DriveBase, Servo) runs on.

On the hub the firmware ticks the scheduler below Python (its hard tick), and in the simulator the
physics step ticks it from MuJoCo's control callback. A host that has only the plain extension (the
CPython test runs) has nothing that ticks it, so the runtime starts the tick the way the firmware's
frozen boot did before the hard tick existed: a periodic `machine.Timer` calling
`motor_process.tick(time.ticks_ms())`. Starting a second tick where one already runs would run every
controller twice per millisecond, so the native module is asked first (`ticks_itself`, when it says),
and otherwise the scheduler is watched for a few milliseconds to see whether anything else ticks it.
"""

import time

from micropython import const

from openbricks import _native, timers

_TICK_HZ = const(1000)
# Long enough for at least two ticks of a running 1 kHz tick, even with a late one in between.
_PROBE_MS = const(5)
# Only hosts without a native tick reach the fallback (the ESP32 firmware ticks itself). It takes the
# Bluetooth button's hardware timer (see openbricks.timers) because no such host runs that button.
_TIMER_ID = timers.BLUETOOTH_BUTTON
_TIMER_ROLE = "motor_process tick"

_state = {"timer": None}


def _tick(_timer):
    _native.motor_process.tick(time.ticks_ms())


def _ticked_elsewhere():
    says = _native.get("ticks_itself")
    if says is not None and (says() if callable(says) else says):
        return True
    # "Not by itself" (or no answer) does not mean nobody ticks it: a timer started earlier may.
    process = _native.motor_process
    before = process.tick_count
    time.sleep_ms(_PROBE_MS)
    return process.tick_count != before


def ensure_running():
    """Make sure motor_process is ticked at 1 kHz; start a machine.Timer tick if nothing else does it.

    Called by every controller that subscribes to motor_process (a DriveBase at construction). Cheap
    to repeat: a tick that is running, ours or the runtime's, is left alone.
    """
    if _ticked_elsewhere():
        return False
    from machine import Timer

    timer = _state["timer"]
    timers.claim(_TIMER_ID, _TIMER_ROLE)
    if timer is None:
        timer = _state["timer"] = Timer(_TIMER_ID)
    timer.init(mode=Timer.PERIODIC, freq=_TICK_HZ, callback=_tick)
    return True


def stop():
    """Stop the tick this module started (tests; a program never needs to)."""
    timer = _state["timer"]
    if timer is not None:
        timer.deinit()
        timers.release(_TIMER_ID, _TIMER_ROLE)
