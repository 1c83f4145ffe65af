"""MicroPython's `time` for a program running on a simulated hub, on its virtual clock.

Installed as `sys.modules["time"]` in the program's process (and in the runtime's tests): sleeps
advance the clock (and the physics behind it in the simulator), ticks_*() read simulated time
(wrapping like the ESP32 port's 30-bit ticks), time()/gmtime() read the simulated RTC (Unix
epoch, UTC, as MicroPython 1.27 on the ESP32). Names MicroPython's time lacks fall through to the
host's module, so host libraries imported later keep working.
"""

try:
    import utime as _host_time  # MicroPython, where `time` may be this module
except ImportError:
    import time as _host_time

# A ticks_*() call on an ESP32-S3 takes a few microseconds of interpreter time: code that only
# spins on the clock still lets time pass, as on a hub.
CPU_US_PER_TICKS_CALL = 2

TICKS_PERIOD = 1 << 30
TICKS_MAX = TICKS_PERIOD - 1
_TICKS_HALFPERIOD = TICKS_PERIOD // 2

_clock = [None]


def bind(clock):
    _clock[0] = clock


def _unbound():
    raise RuntimeError("the simulator's time module is not bound to a simulated clock")


def _sim_clock():
    # `or` rather than a call when bound: a move's wait reads the clock and sleeps every 10 ms.
    return _clock[0] or _unbound()


def ticks_us():
    clock = _clock[0] or _unbound()
    clock.charge_cpu_us(CPU_US_PER_TICKS_CALL)
    return clock.now_us() & TICKS_MAX


def ticks_ms():
    clock = _clock[0] or _unbound()
    clock.charge_cpu_us(CPU_US_PER_TICKS_CALL)
    return clock.now_ms() & TICKS_MAX


def ticks_cpu():
    return ticks_us()


def ticks_add(ticks, delta):
    return (ticks + delta) & TICKS_MAX


def ticks_diff(end, start):
    return ((end - start + _TICKS_HALFPERIOD) & TICKS_MAX) - _TICKS_HALFPERIOD


def sleep_us(us):
    if us >= 0:  # a zero sleep still runs what is due, as on the hub
        _sim_clock().advance_us(int(us))


def sleep_ms(ms):
    if ms >= 0:
        (_clock[0] or _unbound()).advance_us(int(ms * 1000))


def sleep(seconds):
    if seconds >= 0:
        _sim_clock().advance_us(int(seconds * 1_000_000))


def time():
    return _sim_clock().epoch_us() // 1_000_000


def time_ns():
    return _sim_clock().epoch_us() * 1000


# The calendar is computed here rather than borrowed from the host's time module: CPython's
# gmtime returns a 9-field struct_time and its mktime reads the tuple as *local* time, while
# MicroPython's return and take plain 8-tuples in UTC. Doing the arithmetic once gives both
# interpreters the hub's behaviour: UTC, no time zone.
_DAYS_BEFORE_MONTH = (0, 31, 59, 90, 120, 151, 181, 212, 243, 273, 304, 334)
_WEEKDAY_OF_1970_01_01 = 3  # a Thursday; weekdays count from Monday = 0


def _is_leap(year):
    return year % 4 == 0 and (year % 100 != 0 or year % 400 == 0)


def _days_before_year(year):
    """Days from 1970-01-01 to January 1st of `year` (negative before 1970)."""
    y = year - 1
    return y * 365 + y // 4 - y // 100 + y // 400 - 719162


def _days_before_month(year, month):
    return _DAYS_BEFORE_MONTH[month - 1] + (1 if month > 2 and _is_leap(year) else 0)


def gmtime(secs=None):
    """(year, month, mday, hour, minute, second, weekday, yearday), as MicroPython returns it."""
    secs = time() if secs is None else int(secs)
    days, rest = divmod(secs, 86400)
    year = 1970 + days // 366  # close; the loops settle it (it can start high before 1970)
    while _days_before_year(year) > days:
        year -= 1
    while _days_before_year(year + 1) <= days:
        year += 1
    yday = days - _days_before_year(year)
    month = 12
    while _days_before_month(year, month) > yday:
        month -= 1
    mday = yday - _days_before_month(year, month) + 1
    weekday = (days + _WEEKDAY_OF_1970_01_01) % 7
    return (year, month, mday, rest // 3600, rest // 60 % 60, rest % 60, weekday, yday + 1)


def localtime(secs=None):
    return gmtime(secs)  # the hub keeps UTC; the host renders local time


def mktime(tup):
    """Seconds since 1970 for a gmtime()-style tuple (8 or 9 fields); out-of-range fields carry
    over into the next larger one, as on both interpreters."""
    year, month, mday, hour, minute, second = tup[:6]
    year += (month - 1) // 12
    month = (month - 1) % 12 + 1
    days = _days_before_year(year) + _days_before_month(year, month) + mday - 1
    return ((days * 24 + hour) * 60 + minute) * 60 + second


def __getattr__(name):
    return getattr(_host_time, name)
