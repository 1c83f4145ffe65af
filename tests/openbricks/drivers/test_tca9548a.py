"""TCA9548A: mux[n] reaches exactly the chip on channel n, as a drop-in I2C bus."""

from machine import I2C, Pin

from fakes.expect import raises
from fakes.i2c_chips import TCA9548AChip, TCS34725Chip
from openbricks.drivers.tca9548a import TCA9548A
from openbricks.drivers.tcs34725 import TCS34725


def _bus():
    return I2C(0, sda=Pin(15), scl=Pin(16), freq=400_000)


def test_same_address_sensors_on_different_channels_read_their_own_light():
    chip = TCA9548AChip()
    left, right = TCS34725Chip(), TCS34725Chip()
    left.light = (30, 10, 10, 10)  # white
    right.light = (30, 24, 3, 3)  # red
    chip.attach(0, 0x29, left)
    chip.attach(1, 0x29, right)
    mux = TCA9548A(_bus())
    sensors = [TCS34725(mux[0]), TCS34725(mux[1])]
    r0 = sensors[0].rgb()
    r1 = sensors[1].rgb()
    assert r0[0] == r0[1] == r0[2]
    assert r1[0] > 2 * r1[1] and r1[0] > 2 * r1[2]
    # The channels were switched by writing the control byte, one channel at a time.
    assert chip.control in (0x01, 0x02)


def test_channel_is_only_reselected_when_another_channel_was_used():
    chip = TCA9548AChip()
    chip.attach(2, 0x29, TCS34725Chip())
    mux = TCA9548A(_bus())
    sensor = TCS34725(mux[2])
    writes = chip.control_writes
    for _ in range(5):
        sensor.raw()
    assert chip.control_writes == writes
    assert mux.selected() == 0x04


def test_a_mux_that_browned_out_is_reselected_and_the_read_still_succeeds():
    chip = TCA9548AChip()
    sensor_chip = TCS34725Chip()
    sensor_chip.light = (100, 30, 30, 30)
    chip.attach(3, 0x29, sensor_chip)
    sensor = TCS34725(TCA9548A(_bus())[3])
    chip.power_cycle()
    assert sensor.raw()[0] > 0
    assert chip.control == 0x08


def test_scan_on_a_channel_lists_that_channel_only_and_not_the_mux():
    chip = TCA9548AChip()
    chip.attach(0, 0x29, TCS34725Chip())
    chip.attach(5, 0x3C, TCS34725Chip())
    mux = TCA9548A(_bus())
    assert mux[0].scan() == [0x29]
    assert mux[5].scan() == [0x3C]
    assert mux[7].scan() == []


def test_select_and_disable_write_the_control_register():
    chip = TCA9548AChip(address=0x71)
    mux = TCA9548A(_bus(), address=0x71)
    mux.select(6)
    assert chip.control == 0x40
    mux.disable()
    assert chip.control == 0x00
    assert mux.selected() == 0


def test_channel_index_out_of_range_is_refused():
    TCA9548AChip()
    mux = TCA9548A(_bus())
    with raises(IndexError, "0..7"):
        mux[8]
    with raises(ValueError, "0..7"):
        mux.select(-1)


def test_missing_mux_names_its_address_and_the_straps():
    with raises(OSError, "0x70") as err:
        TCA9548A(_bus())
    assert "A0/A1/A2" in str(err.value)


def test_address_outside_the_strap_range_is_refused():
    with raises(ValueError, "0x70..0x77"):
        TCA9548A(_bus(), address=0x29)
