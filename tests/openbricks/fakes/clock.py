"""Virtual time for the hub runtime's tests.

Installed as the `time` functions the runtime uses (MicroPython's sleep_ms and
ticks_*), so a test that "waits" 5 s takes microseconds, and the periodic
machine.Timer callbacks (the control tick, the log pump, the button watcher)
fire at their due times while the program under test sleeps, as on a hub.
"""

try:
    import utime as _host_time  # MicroPython
except ImportError:
    import time as _host_time

TICKS_PERIOD = 1 << 30
TICKS_MAX = TICKS_PERIOD - 1
TICKS_HALFPERIOD = TICKS_PERIOD // 2

# Unix epoch of the moment virtual time started (set by the fake RTC).
EPOCH_2000_S = 946684800

_state = {"now_us": 0, "epoch_base_us": EPOCH_2000_S * 1_000_000, "in_advance": False}
_timers = []  # objects with .next_due_us and .fire(); machine.Timer registers here
# What runs "between bytecodes" on the hub: the fake micropython.schedule queue registers its runner
# here (CPython only; on MicroPython the real VM runs scheduled callbacks itself).
_pending_runner = [None]


def reset():
    _state["now_us"] = 0
    _state["epoch_base_us"] = EPOCH_2000_S * 1_000_000
    _state["in_advance"] = False
    del _timers[:]


def now_us():
    return _state["now_us"]


def register_timer(timer):
    if timer not in _timers:
        _timers.append(timer)


def unregister_timer(timer):
    if timer in _timers:
        _timers.remove(timer)


def set_pending_runner(run_pending):
    _pending_runner[0] = run_pending


def _run_pending():
    run = _pending_runner[0]
    if run is not None:
        run()


def advance_us(us):
    """Move virtual time forward by `us`, firing every timer callback that falls due on the way."""
    target = _state["now_us"] + int(us)
    if _state["in_advance"]:
        # A timer callback that sleeps must not recurse into the timer queue.
        _state["now_us"] = max(_state["now_us"], target)
        return
    _state["in_advance"] = True
    try:
        _run_pending()
        while True:
            due = [t for t in _timers if t.next_due_us is not None and t.next_due_us <= target]
            if not due:
                break
            first = min(due, key=lambda t: t.next_due_us)
            if first.next_due_us > _state["now_us"]:
                _state["now_us"] = first.next_due_us
            first.fire()
            _run_pending()
        _state["now_us"] = max(_state["now_us"], target)
    finally:
        _state["in_advance"] = False


class WorldEvent:
    """Something the outside world does at a virtual time (a button press, a line sliding under a
    sensor). Tests use these rather than machine.Timer: the hub's four hardware timers belong to
    the runtime under test, and a failing world event is a broken test, so it is not swallowed."""

    def __init__(self, delay_us, action, period_us=0):
        self._action = action
        self._period_us = period_us
        self.next_due_us = _state["now_us"] + delay_us
        register_timer(self)

    def fire(self):
        if self._period_us:
            self.next_due_us += self._period_us
        else:
            self.cancel()
        self._action()

    def cancel(self):
        self.next_due_us = None
        unregister_timer(self)


def after_ms(delay_ms, action):
    """Call action() once, `delay_ms` of virtual time from now."""
    return WorldEvent(int(delay_ms * 1000), action)


def every_ms(period_ms, action):
    """Call action() every `period_ms` of virtual time until the returned event is cancelled."""
    return WorldEvent(int(period_ms * 1000), action, int(period_ms * 1000))


def set_epoch_ms(epoch_ms):
    """Make the wall clock read `epoch_ms` (Unix epoch milliseconds) right now."""
    _state["epoch_base_us"] = int(epoch_ms) * 1000 - _state["now_us"]


def epoch_us():
    return _state["epoch_base_us"] + _state["now_us"]


# --- the MicroPython `time` surface -------------------------------------------------


def ticks_us():
    return _state["now_us"] & TICKS_MAX


def ticks_ms():
    return (_state["now_us"] // 1000) & TICKS_MAX


def ticks_cpu():
    return ticks_us()


def ticks_add(ticks, delta):
    return (ticks + delta) & TICKS_MAX


def ticks_diff(end, start):
    return ((end - start + TICKS_HALFPERIOD) & TICKS_MAX) - TICKS_HALFPERIOD


def sleep_us(us):
    if us >= 0:  # a zero sleep still runs what is scheduled, as on the hub
        advance_us(us)


def sleep_ms(ms):
    if ms >= 0:
        advance_us(int(ms * 1000))


def sleep(seconds):
    if seconds >= 0:
        advance_us(int(seconds * 1_000_000))


def time():
    return epoch_us() // 1_000_000


def time_ns():
    return epoch_us() * 1000


# The calendar is computed here rather than borrowed from the host's time module: CPython's
# gmtime returns a 9-field struct_time and its mktime reads the tuple as *local* time (so the fake
# RTC drifted by the machine's UTC offset), while MicroPython's return and take plain 8-tuples in UTC.
# Doing the arithmetic once gives both interpreters the hub's behaviour: UTC, no time zone.
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
    return gmtime(secs)  # the hub keeps UTC


def mktime(tup):
    """Seconds since 1970 for a gmtime()-style tuple (8 or 9 fields); out-of-range fields carry
    over into the next larger one, as on both interpreters."""
    year, month, mday, hour, minute, second = tup[:6]
    year += (month - 1) // 12
    month = (month - 1) % 12 + 1
    days = _days_before_year(year) + _days_before_month(year, month) + mday - 1
    return ((days * 24 + hour) * 60 + minute) * 60 + second


MICROPYTHON_TIME_NAMES = (
    "ticks_us",
    "ticks_ms",
    "ticks_cpu",
    "ticks_add",
    "ticks_diff",
    "sleep_us",
    "sleep_ms",
    "sleep",
    "time",
    "time_ns",
    "gmtime",
    "localtime",
    "mktime",
)


def __getattr__(name):
    # Everything the runtime does not use (perf_counter, strftime, ...) stays the host's.
    return getattr(_host_time, name)
