"""wait() and StopWatch keep virtual time the way a user program sees it on the hub."""

import time

from fakes.expect import raises
from openbricks import estop
from openbricks.tools import StopWatch, wait


def test_wait_sleeps_exactly_the_requested_milliseconds():
    start = time.ticks_ms()
    wait(1234)
    assert time.ticks_diff(time.ticks_ms(), start) == 1234
    wait(0)
    wait(-5)
    assert time.ticks_diff(time.ticks_ms(), start) == 1234


def test_a_stop_press_ends_a_long_wait_within_one_slice():
    import machine

    trigger = machine.Timer(3)
    trigger.init(mode=machine.Timer.ONE_SHOT, period=1000, callback=lambda _t: estop.engage("test stop"))
    start = time.ticks_ms()
    try:
        with raises(estop.EStopError, "wait() refused: e-stop engaged (test stop)"):
            wait(60_000)
        assert time.ticks_diff(time.ticks_ms(), start) <= 1020
    finally:
        estop.clear()


def test_stopwatch_counts_pauses_and_resets():
    watch = StopWatch()
    time.sleep_ms(100)
    assert watch.time() == 100
    watch.pause()
    time.sleep_ms(500)
    assert watch.time() == 100
    watch.resume()
    time.sleep_ms(50)
    assert watch.time() == 150
    watch.reset()
    assert watch.time() == 0
    time.sleep_ms(30)
    assert watch.time() == 30


def test_paused_stopwatch_reset_stays_paused_at_zero():
    watch = StopWatch()
    watch.pause()
    time.sleep_ms(10)
    watch.reset()
    time.sleep_ms(10)
    assert watch.time() == 0
    watch.resume()
    time.sleep_ms(7)
    assert watch.time() == 7


def test_stopwatch_survives_the_tick_counter_wrapping():
    time.sleep_ms((1 << 30) - 100)  # ticks_ms wraps at 2**30 on MicroPython
    watch = StopWatch()
    time.sleep_ms(250)
    assert watch.time() == 250
