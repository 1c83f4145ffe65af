"""Range finder models: the ray finds the wall the robot faces, at the distance geometry says,
through each chip's own measurement protocol and limits."""

import math

import pytest

from openbricks_sim.sensors.distance import (
    SOUND_MM_PER_US,
    ForwardRay,
    HCSR04Model,
    VL53L0XModel,
    VL53L1XModel,
    sonar_ray,
)
from openbricks_sim.sensors.registers import physics_clock_us
from openbricks_sim.worlds import arena

from .placed import place, step_ms

SITE_AHEAD_MM = 95.0  # the chassis' distance site: 95 mm ahead of the axle midpoint
EAST_WALL_X_MM = arena.INNER_MM[0] / 2


def in_arena(x_mm=-500.0, y_mm=0.0, heading_deg=0.0):
    return place("arena", x_mm, y_mm, heading_deg)


def l0x_range(chip, model, data, wait_ms=40):
    chip.write_mem(0x00, b"\x01")
    step_ms(model, data, wait_ms)
    assert chip.read_mem(0x13, 1)[0] & 0x07, "no sample flagged after the ranging time"
    hi, lo = chip.read_mem(0x1E, 2)
    chip.write_mem(0x0B, b"\x01")
    return (hi << 8) | lo


def test_ray_reaches_the_wall_ahead_at_the_geometric_distance():
    model, data = in_arena()
    expected = EAST_WALL_X_MM - (-500.0 + SITE_AHEAD_MM)
    assert ForwardRay(model, data).range_mm() == pytest.approx(expected, abs=0.5)


def test_ray_ignores_the_robots_own_body_and_turns_with_it():
    model, data = in_arena(0.0, 0.0, -90.0)  # facing +y: the north wall
    expected = arena.INNER_MM[1] / 2 - SITE_AHEAD_MM
    assert ForwardRay(model, data).range_mm() == pytest.approx(expected, abs=0.5)


def test_vl53l0x_reports_the_wall_within_two_mm_after_its_ranging_time():
    model, data = in_arena()
    chip = VL53L0XModel(ForwardRay(model, data), physics_clock_us(data))
    assert chip.read_mem(0xC0, 1) == b"\xee"
    chip.write_mem(0x00, b"\x01")
    step_ms(model, data, 10)
    assert chip.read_mem(0x13, 1)[0] & 0x07 == 0  # still ranging
    step_ms(model, data, 30)
    expected = EAST_WALL_X_MM - (-500.0 + SITE_AHEAD_MM)
    hi, lo = chip.read_mem(0x1E, 2)
    assert abs(((hi << 8) | lo) - expected) <= 2
    chip.write_mem(0x0B, b"\x01")
    assert chip.read_mem(0x13, 1)[0] & 0x07 == 0  # cleared until the next ranging


def test_vl53l0x_beyond_two_metres_reads_no_target():
    model, data = place("wro", -1011.0, 0.0, 0.0)  # facing the far end of the table, 2.2 m away
    chip = VL53L0XModel(ForwardRay(model, data), physics_clock_us(data))
    assert l0x_range(chip, model, data) == 8190


def test_vl53l1x_ranges_long_and_flags_signal_fail_past_its_reach():
    model, data = place("wro", -1011.0, 0.0, 0.0)
    chip = VL53L1XModel(ForwardRay(model, data), physics_clock_us(data))
    assert chip.read_mem(0x010F, 2, 16) == b"\xea\xcc"
    step_ms(model, data, 3)
    assert chip.read_mem(0x00E5, 1, 16)[0] & 0x01  # booted
    chip.write_mem(0x0086, b"\x01", 16)
    chip.write_mem(0x0087, b"\x40", 16)
    assert chip.read_mem(0x0031, 1, 16)[0] & 0x01  # not ready yet (active low)
    step_ms(model, data, 55)
    assert chip.read_mem(0x0031, 1, 16)[0] & 0x01 == 0
    assert chip.read_mem(0x0089, 1, 16)[0] & 0x1F == 9
    mm = int.from_bytes(chip.read_mem(0x0096, 2, 16), "big")
    expected = 2362.0 / 2 - (-1011.0 + SITE_AHEAD_MM)
    assert abs(mm - expected) <= 2
    near = VL53L1XModel(ForwardRay(model, data), physics_clock_us(data), max_mm=1000.0)
    near.write_mem(0x0087, b"\x40", 16)
    step_ms(model, data, 55)
    assert near.read_mem(0x0089, 1, 16)[0] & 0x1F == 4


def test_hcsr04_echo_is_the_round_trip_and_its_cone_catches_an_off_axis_pillar():
    # The sensor 100 mm from the pillar's west face and 12 mm to the side of its south edge: the
    # laser passes it and sees the east wall; the sonar's 15 degree cone catches the pillar.
    px, py, side = arena.PILLAR_MM
    x = px - side / 2 - 100.0 - SITE_AHEAD_MM
    y = py - side / 2 - 12.0
    model, data = in_arena(x, y, 0.0)
    laser = ForwardRay(model, data).range_mm()
    sonar = HCSR04Model(sonar_ray(model, data), noise_mm=0.0)
    sonar.trigger()
    width = sonar.echo_pulse_us(1)
    assert laser == pytest.approx(EAST_WALL_X_MM - (x + SITE_AHEAD_MM), abs=0.5)
    assert width * SOUND_MM_PER_US / 2 == pytest.approx(100.0 / math.cos(math.radians(7.5)), abs=12.0)


def test_hcsr04_echoes_once_per_trigger_pulse():
    model, data = in_arena()
    sonar = HCSR04Model(sonar_ray(model, data))
    assert sonar.echo_pulse_us(1) == -1  # never triggered
    sonar.trig_driven(18, 1)
    assert sonar.echo_pulse_us(1) == -1  # TRIG still high: the burst leaves on the falling edge
    sonar.trig_driven(18, 0)
    width = sonar.echo_pulse_us(1)
    assert width * SOUND_MM_PER_US / 2 == pytest.approx(1205.0, abs=5.0)
    assert sonar.echo_pulse_us(1) == -1  # one echo per ping


def test_hcsr04_nothing_within_range_gives_no_echo():
    model, data = in_arena()
    sonar = HCSR04Model(sonar_ray(model, data), max_mm=1000.0)
    sonar.trigger()
    assert sonar.echo_pulse_us(1) == -1


def test_noise_is_seeded():
    model, data = in_arena()
    a = HCSR04Model(sonar_ray(model, data), seed=1)
    b = HCSR04Model(sonar_ray(model, data), seed=1)

    def pings(sonar):
        out = []
        for _ in range(5):
            sonar.trigger()
            out.append(sonar.echo_pulse_us(1))
        return out

    assert pings(a) == pings(b)
