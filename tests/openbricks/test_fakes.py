"""The fakes behave like the hub where the runtime depends on it."""

import time

import machine


def test_sleep_fires_periodic_timers_at_their_due_times():
    seen = []
    t = machine.Timer(0)
    t.init(mode=machine.Timer.PERIODIC, period=10, callback=lambda _t: seen.append(time.ticks_ms()))
    time.sleep_ms(35)
    t.deinit()
    assert seen == [10, 20, 30]
    assert time.ticks_ms() == 35


def test_ticks_diff_wraps():
    assert time.ticks_diff(time.ticks_add(0, -5), 0) == -5
    assert time.ticks_diff(3, time.ticks_add(3, -((1 << 29) - 1))) == (1 << 29) - 1
