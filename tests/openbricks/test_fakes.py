"""The fakes behave like the hub where the runtime depends on it."""

import time

import esp32
import machine
import micropython

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


def test_only_the_four_hardware_timers_exist():
    for bad_id in (-1, 4):
        with raises(ValueError, "Timer(%d) doesn't exist" % bad_id):
            machine.Timer(bad_id)  # the ESP32 port has no virtual timers


def test_a_timer_id_names_one_hardware_timer_so_a_second_init_replaces_the_first_callback():
    seen = []
    machine.Timer(2).init(period=10, callback=lambda _t: seen.append("first"))
    machine.Timer(2).init(period=10, callback=lambda _t: seen.append("second"))
    time.sleep_ms(25)
    machine.Timer(2).deinit()
    assert seen == ["second", "second"]


def test_an_exception_in_a_timer_callback_is_dropped_and_the_timer_keeps_firing():
    seen = []

    def failing(_t):
        seen.append(time.ticks_ms())
        raise ValueError("callback bug")

    t = machine.Timer(1)
    t.init(period=10, callback=failing)
    time.sleep_ms(30)  # the sleeping program never sees the ValueError
    t.deinit()
    assert seen == [10, 20, 30]


def test_get_blob_refuses_a_buffer_shorter_than_the_blob():
    nvs = esp32.NVS("fakes")
    nvs.set_blob("name", b"twelve bytes")
    nvs.commit()
    with raises(OSError):
        nvs.get_blob("name", bytearray(4))
    buf = bytearray(16)
    assert nvs.get_blob("name", buf) == 12
    assert bytes(buf[:12]) == b"twelve bytes"


def test_scheduled_callbacks_run_later_and_a_full_queue_refuses_more():
    ran = []
    flood = {"queued": 0, "error": None, "ran_during_flood": None}

    def flood_queue(_arg):
        # Inside a scheduled callback the scheduler cannot drain, so the queue only fills.
        try:
            while flood["queued"] < 100:
                micropython.schedule(ran.append, flood["queued"])
                flood["queued"] += 1
        except RuntimeError as exc:
            flood["error"] = str(exc)
        flood["ran_during_flood"] = len(ran)

    micropython.schedule(flood_queue, None)
    time.sleep_ms(1)
    time.sleep_ms(1)
    assert flood["error"] == "schedule queue full"
    assert flood["ran_during_flood"] == 0
    assert ran == list(range(flood["queued"]))
