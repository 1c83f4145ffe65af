"""MicroPython's `time` for a program running in the simulator, on the simulated clock.

Installed as `sys.modules["time"]` in the program's process: sleeps advance
the physics, ticks_*() read simulated time (wrapping like the ESP32 port's
30-bit ticks), time()/gmtime() read the simulated RTC (Unix epoch, as
MicroPython 1.27 on the ESP32). Names MicroPython's time lacks fall through
to the host's module, so host libraries imported later keep working.
"""

import time as _host_time

from ..clock import CPU_US_PER_TICKS_CALL

TICKS_PERIOD = 1 << 30
TICKS_MAX = TICKS_PERIOD - 1
_TICKS_HALFPERIOD = TICKS_PERIOD // 2

_clock = [None]


def bind(clock):
    _clock[0] = clock


def _sim_clock():
    clock = _clock[0]
    if clock is None:
        raise RuntimeError("the simulator's time module is not bound to a simulated clock")
    return clock


def ticks_us():
    clock = _sim_clock()
    clock.charge_cpu_us(CPU_US_PER_TICKS_CALL)
    return clock.now_us() & TICKS_MAX


def ticks_ms():
    clock = _sim_clock()
    clock.charge_cpu_us(CPU_US_PER_TICKS_CALL)
    return clock.now_ms() & TICKS_MAX


def ticks_cpu():
    return ticks_us()


def ticks_add(ticks, delta):
    return (ticks + delta) & TICKS_MAX


def ticks_diff(end, start):
    return ((end - start + _TICKS_HALFPERIOD) & TICKS_MAX) - _TICKS_HALFPERIOD


def sleep_us(us):
    if us > 0:
        _sim_clock().advance_us(int(us))


def sleep_ms(ms):
    if ms > 0:
        _sim_clock().advance_us(int(ms * 1000))


def sleep(seconds):
    if seconds > 0:
        _sim_clock().advance_us(int(seconds * 1_000_000))


def time():
    return _sim_clock().epoch_us() // 1_000_000


def time_ns():
    return _sim_clock().epoch_us() * 1000


def gmtime(secs=None):
    t = _host_time.gmtime(time() if secs is None else secs)
    # MicroPython's 8-tuple: (year, month, mday, hour, minute, second, weekday, yearday).
    return (t.tm_year, t.tm_mon, t.tm_mday, t.tm_hour, t.tm_min, t.tm_sec, t.tm_wday, t.tm_yday)


def localtime(secs=None):
    return gmtime(secs)  # the hub keeps UTC; the host renders local time


def mktime(t):
    import calendar

    year, month, mday, hour, minute, second = t[:6]
    return calendar.timegm((year, month, mday, hour, minute, second, 0, 0, 0))


def __getattr__(name):
    return getattr(_host_time, name)
