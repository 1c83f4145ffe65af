"""The TCS34725 model over the mats: the counts a driver reads are the colour under the sensor,
integrated the way the chip integrates, and the TCA9548A model routes two of them."""

import struct

import pytest

from openbricks_sim.sensors.color import TCS34725Model
from openbricks_sim.sensors.mat import GroundProbe
from openbricks_sim.sensors.mux import TCA9548AModel
from openbricks_sim.sensors.registers import physics_clock_us
from openbricks_sim.worlds import WORLDS, zones

from .placed import place, step_ms

CMD, AUTO = 0x80, 0x20


def sensor(alias, x_mm, y_mm, heading_deg=0.0, site="color_0", **kw):
    model, data = place(alias, x_mm, y_mm, heading_deg)
    return TCS34725Model(GroundProbe(model, data), site, physics_clock_us(data), **kw), model, data


def power_up(chip, cycles=1, gain_code=2):
    """What the driver sends: ATIME, CONTROL, PON, then PON|AEN."""
    chip.write_mem(CMD | 0x01, bytes([256 - cycles]))
    chip.write_mem(CMD | 0x0F, bytes([gain_code]))
    chip.write_mem(CMD | 0x00, b"\x01")
    chip.write_mem(CMD | 0x00, b"\x03")


def crgb(chip):
    return struct.unpack("<4H", chip.read_mem(CMD | AUTO | 0x14, 8))


def chromaticity(c, r, g, b):
    return (r / c, g / c, b / c)


def test_identity_and_no_data_until_the_first_integration_completes():
    chip, model, data = sensor("zones", 500, 0)  # colour sensors over the red zone
    assert chip.read_mem(CMD | 0x12, 1) == b"\x44"
    power_up(chip)
    assert chip.read_mem(CMD | 0x13, 1)[0] & 0x01 == 0
    assert crgb(chip) == (0, 0, 0, 0)
    step_ms(model, data, 5)  # 2.4 ms warm-up after PON, then one 2.4 ms cycle
    assert chip.read_mem(CMD | 0x13, 1)[0] & 0x01 == 1
    assert crgb(chip)[0] > 0


def read_after_integration(alias, x_mm, y_mm, heading_deg=0.0, site="color_0", cycles=1, gain_code=2):
    chip, model, data = sensor(alias, x_mm, y_mm, heading_deg, site)
    power_up(chip, cycles, gain_code)
    step_ms(model, data, 3 + 2.4 * cycles + 1)
    return crgb(chip)


def test_each_zone_colour_dominates_its_channel_and_white_is_balanced():
    # The robot's centre at (x, y): the colour sensors sit 60 mm ahead, 20 mm either side.
    red = chromaticity(*read_after_integration("zones", 440, 0))
    green = chromaticity(*read_after_integration("zones", 440, 300))
    blue = chromaticity(*read_after_integration("zones", 440, -300))
    white = chromaticity(*read_after_integration("zones", -500, 0))
    assert red[0] > 0.85 and red[1] < 0.1 and red[2] < 0.1
    assert green[1] > 0.6 and green[1] > 3 * green[0]
    assert blue[2] > 0.6 and blue[2] > 3 * blue[0]
    assert all(abs(ch - 1 / 3) < 0.02 for ch in white)


def test_white_mat_fills_most_of_the_range_at_the_driver_defaults_and_black_line_almost_none():
    full_scale = 1024  # one 2.4 ms cycle
    white = read_after_integration("zones", -500, 0)[0]
    # The line track's start line runs under the robot's centre line; color_0 is 20 mm left of it.
    x, y, _ = WORLDS["line_track"].start_mm_deg
    on_line = read_after_integration("line_track", x, y - 20)[0]
    assert 0.75 * full_scale < white < 0.95 * full_scale
    assert on_line < 0.05 * full_scale


def test_counts_scale_with_integration_time_and_gain_and_saturate_at_full_scale():
    one = read_after_integration("zones", 440, 0, cycles=1, gain_code=1)[1]
    ten = read_after_integration("zones", 440, 0, cycles=10, gain_code=1)[1]
    assert ten == pytest.approx(10 * one, rel=0.05)
    saturated = read_after_integration("zones", -500, 0, cycles=1, gain_code=3)  # 60x on white
    assert saturated[0] == 1024


def test_the_two_colour_sensors_see_either_side_of_a_line_edge():
    # Centre the robot on the red zone's north edge (y = 120): color_0, 20 mm to the left, over the
    # white gap before the green zone; color_1, 20 mm to the right, over red.
    left = chromaticity(*read_after_integration("zones", 440, 120, site="color_0"))
    right = chromaticity(*read_after_integration("zones", 440, 120, site="color_1"))
    assert abs(left[0] - 1 / 3) < 0.03
    assert right[0] > 0.85


def test_reading_moves_with_the_robot():
    chip, model, data = sensor("zones", 440, 0)
    power_up(chip)
    step_ms(model, data, 6)
    before = crgb(chip)
    # Nothing moved: the latched integration is re-read as is, not re-measured.
    assert crgb(chip) == before
    data.qpos[1] += 0.3  # slide the robot 300 mm left, onto green
    step_ms(model, data, 3)
    c, r, g, b = crgb(chip)
    assert g > 3 * r


def test_mux_connects_a_channel_to_the_bus_and_two_same_address_sensors_collide():
    model, data = place("zones", 440, 120)
    probe, clock = GroundProbe(model, data), physics_clock_us(data)
    bus = {}
    mux = TCA9548AModel(bus)
    left = TCS34725Model(probe, "color_0", clock)
    right = TCS34725Model(probe, "color_1", clock)
    mux.attach(0, 0x29, left)
    mux.attach(1, 0x29, right)
    assert bus == {0x70: mux}  # every channel off after power-up
    mux.write(b"\x02")
    assert mux.read(1) == b"\x02"
    assert bus[0x29] is right
    mux.write(b"\x03")
    with pytest.raises(OSError, match="two devices answer at 0x29"):
        bus[0x29].read_mem(CMD | 0x12, 1, 8)
    mux.write(b"\x00")
    assert 0x29 not in bus


def test_mux_channel_and_a_chip_wired_straight_to_the_bus_collide_and_the_chip_comes_back():
    model, data = place("zones", 440, 120)
    probe, clock = GroundProbe(model, data), physics_clock_us(data)
    bare = TCS34725Model(probe, "color_0", clock)
    bus = {0x29: bare}
    mux = TCA9548AModel(bus)
    mux.attach(0, 0x29, TCS34725Model(probe, "color_1", clock))
    mux.write(b"\x01")
    with pytest.raises(OSError):
        bus[0x29].read_mem(CMD | 0x12, 1, 8)
    mux.write(b"\x00")
    assert bus[0x29] is bare


def test_a_missing_site_is_named():
    model, data = place("zones", 0, 0)
    with pytest.raises(ValueError, match="color_7"):
        TCS34725Model(GroundProbe(model, data), "color_7", physics_clock_us(data))


def test_zone_table_and_mat_agree_for_every_coloured_zone():
    for name, (x0, y0, x1, y1, rgb) in zones.ZONES.items():
        cx, cy = (x0 + x1) / 2, (y0 + y1) / 2
        c, r, g, b = read_after_integration("zones", cx - 60, cy - 20)  # put color_0 on the centre
        strongest = max(range(3), key=lambda i: rgb[i])
        if max(rgb) - min(rgb) > 100:
            assert max(range(3), key=lambda i: (r, g, b)[i]) == strongest, name
