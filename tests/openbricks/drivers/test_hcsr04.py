"""HC-SR04: trigger pulse, echo timing to millimetres, no-echo and pin misuse."""

import time

from machine import board

from fakes.expect import raises
from openbricks import pins
from openbricks.distance import DistanceSensor
from openbricks.drivers.hcsr04 import HCSR04


def test_echo_width_converts_to_millimetres_at_the_speed_of_sound():
    sensor = HCSR04(trig=5, echo=6)
    assert isinstance(sensor, DistanceSensor)
    board.set_pulse(6, 3500)  # ~60 cm round trip
    assert sensor.distance_mm() == 600
    board.set_pulse(6, 583)
    assert sensor.distance_mm() == 100


def test_trigger_is_left_low_after_the_pulse():
    sensor = HCSR04(trig=5, echo=6)
    board.set_pulse(6, 1000)
    sensor.distance_mm()
    assert board.pins[5].value() == 0


def test_no_echo_reads_minus_one():
    sensor = HCSR04(trig=5, echo=6, timeout_us=25_000)
    board.set_pulse(6, -1)
    assert sensor.distance_mm() == -1
    board.set_pulse(6, -2)  # echo stuck high
    assert sensor.distance_mm() == -1


def test_back_to_back_readings_are_spaced_so_old_echoes_die_out():
    sensor = HCSR04(trig=5, echo=6)
    board.set_pulse(6, 1000)
    sensor.distance_mm()
    start = time.ticks_ms()
    sensor.distance_mm()
    assert time.ticks_diff(time.ticks_ms(), start) >= 58


def test_a_pin_the_runtime_owns_is_refused_naming_it():
    pins.claim(39, "program button", owner="launcher")
    with raises(pins.ReservedPinError, "GPIO 39") as err:
        HCSR04(trig=39, echo=6)
    assert "program button" in str(err.value)


def test_a_flash_pin_is_refused_on_the_s3():
    pins.set_chip("esp32s3")
    with raises(pins.ReservedPinError, "GPIO 27"):
        HCSR04(trig=5, echo=27)
