"""Virtual time for the hub runtime's tests: the simulator's clock with no physics behind it.

`time` for the runtime is the simulator's (sim/shim/mptime.py) on a fresh
sim/shim/virtual_clock.VirtualClock each test, so a test that "waits" 5 s takes
microseconds, and the machine.Timer callbacks (the control tick, the log pump,
the button watcher) fire at their due times while the program under test
sleeps, as on a hub. This module is the test's side of that clock: reading it,
and the outside world's events on it.
"""

from .hardware import mptime, virtual_clock

# Unix epoch of the moment virtual time starts (the RTC's reset value).
EPOCH_2000_S = 946684800

_clock = [None]


def reset():
    """A fresh clock at 0 us, its RTC at 2000-01-01, with nothing scheduled."""
    _clock[0] = virtual_clock.VirtualClock(0, EPOCH_2000_S * 1000)
    mptime.bind(_clock[0])
    return _clock[0]


def current():
    """The test's clock, as the hardware model binds to it."""
    return _clock[0]


def now_us():
    return _clock[0].now_us()


def advance_us(us):
    """Move virtual time forward by `us`, firing every callback that falls due on the way."""
    _clock[0].advance_us(us)


def set_epoch_ms(epoch_ms):
    """Make the wall clock read `epoch_ms` (Unix epoch milliseconds) right now."""
    _clock[0].set_epoch_ms(epoch_ms)


def epoch_us():
    return _clock[0].epoch_us()


# Something the outside world does at a virtual time (a button press, a line sliding under a
# sensor). Tests use these rather than machine.Timer: the hub's four hardware timers belong to
# the runtime under test, and a failing world event is a broken test, so it is not swallowed.


def after_ms(delay_ms, action):
    """Call action() once, `delay_ms` of virtual time from now; the handle's cancel() calls it off."""
    return _clock[0].schedule(action, int(delay_ms * 1000))


def every_us(period_us, action):
    """Call action() every `period_us` of virtual time until the returned handle is cancelled."""
    return _clock[0].schedule(action, period_us, period_us)


def every_ms(period_ms, action):
    return every_us(int(period_ms * 1000), action)


reset()
