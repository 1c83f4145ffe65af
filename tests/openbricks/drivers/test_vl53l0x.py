"""VL53L0X: the manual's single-shot register sequence against a register-level chip."""

import time

from machine import I2C, board

from fakes.expect import raises
from fakes.i2c_chips import TCS34725Chip, VL53L0XChip
from openbricks.distance import DistanceSensor
from openbricks.drivers.vl53l0x import VL53L0X


def _sensor(chip, **kwargs):
    board.attach_i2c(0, 0x29, chip)
    return VL53L0X(I2C(0), **kwargs)


def test_reads_the_target_distance_after_one_ranging():
    chip = VL53L0XChip()
    sensor = _sensor(chip)
    assert isinstance(sensor, DistanceSensor)
    chip.distance_mm = 437
    assert sensor.distance_mm() == 437
    assert chip.rangings == 1


def test_each_reading_is_a_fresh_measurement_and_clears_the_interrupt():
    chip = VL53L0XChip()
    sensor = _sensor(chip)
    chip.distance_mm = 300
    assert sensor.distance_mm() == 300
    assert chip.written(0x0B) == [0x01]
    chip.distance_mm = 120
    assert sensor.distance_mm() == 120
    assert chip.rangings == 2


def test_a_reading_waits_for_the_ranging_to_finish():
    chip = VL53L0XChip(ranging_ms=40)
    sensor = _sensor(chip)
    start = time.ticks_ms()
    sensor.distance_mm()
    assert time.ticks_diff(time.ticks_ms(), start) >= 40


def test_nothing_in_range_is_minus_one():
    chip = VL53L0XChip()
    sensor = _sensor(chip)
    chip.distance_mm = None  # the chip reports 8190
    assert sensor.distance_mm() == -1


def test_a_wedged_chip_times_out_with_its_address_and_the_budget():
    chip = VL53L0XChip()
    sensor = _sensor(chip, timeout_ms=120)
    chip.stalled = True
    with raises(OSError, "within 120 ms") as err:
        sensor.distance_mm()
    assert "0x29" in str(err.value)


def test_another_chip_at_0x29_is_not_mistaken_for_a_range_finder():
    with raises(OSError, "not a VL53L0X"):
        _sensor(TCS34725Chip())


def test_nothing_on_the_bus_says_so():
    with raises(OSError, "no VL53L0X answers at I2C address 0x29"):
        VL53L0X(I2C(0))
