"""TCS34725 against a register-level chip: identity, integration setup, colour and brightness scaling."""

from machine import I2C, board

from fakes.expect import raises
from fakes.i2c_chips import TCS34725Chip, VL53L0XChip
from openbricks.drivers.tcs34725 import TCS34725
from openbricks.interfaces import ColorSensor


def _sensor(chip, **kwargs):
    board.attach_i2c(0, 0x29, chip)
    return TCS34725(I2C(0), **kwargs)


def test_is_a_color_sensor():
    assert isinstance(_sensor(TCS34725Chip()), ColorSensor)


def test_construction_programs_integration_time_and_gain_then_powers_on():
    chip = TCS34725Chip()
    _sensor(chip, integration_ms=24, gain=4)
    assert chip.cycles() == 10
    assert chip.gain() == 4
    assert chip.written(0x00) == [0x01, 0x03]  # PON, then PON|AEN after the warm-up


def test_first_reading_is_already_a_real_integration_not_zeros():
    chip = TCS34725Chip()
    chip.light = (50, 20, 15, 10)
    sensor = _sensor(chip, integration_ms=240, gain=1)
    assert sensor.raw() == (5000, 2000, 1500, 1000)


def test_white_reads_near_full_scale_at_any_brightness():
    chip = TCS34725Chip()
    sensor = _sensor(chip, gain=1)
    for level in (30, 300):
        chip.light = (level * 3, level, level, level)
        assert sensor.rgb() == (255, 255, 255)


def test_colours_keep_their_order_and_darkness_is_black():
    chip = TCS34725Chip()
    sensor = _sensor(chip, gain=1)
    chip.light = (600, 60, 330, 210)  # a green-blue object
    r, g, b = sensor.rgb()
    assert g > b > r
    chip.light = (0, 0, 0, 0)
    assert sensor.rgb() == (0, 0, 0)


def test_ambient_is_percent_of_the_saturation_count_for_the_integration_time():
    chip = TCS34725Chip()
    sensor = _sensor(chip, integration_ms=2.4, gain=1)  # saturates at 1024 counts
    chip.light = (512, 0, 0, 0)
    assert sensor.ambient() == 50
    chip.light = (5000, 0, 0, 0)
    assert sensor.ambient() == 100


def test_longer_integration_raises_the_saturation_point_to_the_16_bit_cap():
    chip = TCS34725Chip()
    sensor = _sensor(chip, integration_ms=614.4, gain=1)  # 256 cycles: capped at 65535
    chip.light = (128, 0, 0, 0)  # 32768 counts
    assert sensor.ambient() == 50


def test_a_different_chip_at_0x29_is_named_in_the_error():
    with raises(OSError, "not a TCS34725") as err:
        _sensor(VL53L0XChip())
    assert "0x29" in str(err.value)


def test_nothing_on_the_bus_says_so():
    with raises(OSError, "no TCS34725 answers"):
        TCS34725(I2C(0))


def test_bad_gain_or_integration_time_lists_the_valid_values():
    with raises(ValueError, "1, 4, 16, 60"):
        _sensor(TCS34725Chip(), gain=8)
    with raises(ValueError, "2.4 .. 614.4"):
        _sensor(TCS34725Chip(), integration_ms=1000)
