"""The fakes behave like the hub where the runtime depends on it."""

import time

import machine

from fakes.expect import raises


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


def test_the_calendar_is_utc_in_micropython_8_tuples():
    assert time.gmtime(0) == (1970, 1, 1, 0, 0, 0, 3, 1)  # a Thursday (Monday is 0), day 1
    leap_day = time.gmtime(951782400)
    assert leap_day == (2000, 2, 29, 0, 0, 0, 1, 60)
    assert time.mktime(leap_day) == 951782400
    assert time.mktime((2024, 13, 1, 0, 0, 0, 0, 0)) == time.mktime((2025, 1, 1, 0, 0, 0, 0, 0))


def test_the_rtc_reads_back_what_was_set_whatever_the_host_time_zone():
    rtc = machine.RTC()
    rtc.datetime((2026, 3, 14, 5, 12, 30, 45, 250000))
    time.sleep_ms(1500)
    assert rtc.datetime() == (2026, 3, 14, 5, 12, 30, 46, 750000)
    assert time.time() == time.mktime((2026, 3, 14, 12, 30, 46, 0, 0))


def test_pin_irq_takes_only_what_the_esp32_port_takes():
    pin = machine.Pin(7, machine.Pin.IN)
    with raises(TypeError):
        pin.irq(lambda _p: None, machine.Pin.IRQ_RISING, hard=True)  # no hard pin IRQs on the ESP32
