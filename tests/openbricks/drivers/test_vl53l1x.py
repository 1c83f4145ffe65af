"""VL53L1X: 16-bit register addressing, boot wait, single-shot ranging and range status."""

import time

from machine import I2C, board

from fakes.expect import raises
from fakes.i2c_chips import VL53L0XChip, VL53L1XChip
from openbricks.distance import DistanceSensor
from openbricks.drivers.vl53l1x import VL53L1X


def _sensor(chip, **kwargs):
    board.attach_i2c(0, 0x29, chip)
    return VL53L1X(I2C(0), **kwargs)


def test_reads_the_target_distance():
    chip = VL53L1XChip()
    sensor = _sensor(chip)
    assert isinstance(sensor, DistanceSensor)
    chip.distance_mm = 2750
    assert sensor.distance_mm() == 2750
    assert chip.written(0x87) == [0x40]


def test_construction_waits_for_the_chip_firmware_to_boot():
    chip = VL53L1XChip(boot_ms=30)
    start = time.ticks_ms()
    _sensor(chip)
    assert time.ticks_diff(time.ticks_ms(), start) >= 30


def test_a_chip_that_never_boots_is_reported():
    with raises(OSError, "did not finish booting"):
        _sensor(VL53L1XChip(boot_ms=10_000))


def test_a_late_result_of_an_abandoned_ranging_is_not_returned_as_the_next_one():
    chip = VL53L1XChip()
    sensor = _sensor(chip)
    chip.finish_late(333)
    chip.distance_mm = 1500
    assert sensor.distance_mm() == 1500


def test_nothing_in_range_is_minus_one():
    chip = VL53L1XChip()
    sensor = _sensor(chip)
    chip.distance_mm = None
    assert sensor.distance_mm() == -1


def test_the_vl53l4cd_variant_is_accepted_and_named():
    sensor = _sensor(VL53L1XChip(model_id=0xEBAA))
    assert sensor.model == "VL53L4CD"


def test_a_vl53l0x_at_the_same_address_points_to_its_own_driver():
    with raises(OSError, "openbricks.drivers.vl53l0x"):
        _sensor(VL53L0XChip())


def test_a_measurement_that_never_completes_times_out():
    chip = VL53L1XChip(ranging_ms=500)
    sensor = _sensor(chip, timeout_ms=100)
    with raises(OSError, "within 100 ms"):
        sensor.distance_mm()
