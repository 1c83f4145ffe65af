"""Closed-loop moves of the drivebase core on a simulated chassis: where the robot really ends up."""

import math

import pytest

import openbricks_native as native
from tests.firmware.native.drivebase_rig import (
    AXLE_TRACK_MM,
    MM_PER_WHEEL_DEG,
    WHEEL_DIAMETER_MM,
    Chassis,
    Rig,
)

SETTLE_MS = 500  # after done(): long enough for any creep or rebound to show


def new_rig(chassis=None, **settings):
    db = native.DriveBase(WHEEL_DIAMETER_MM, AXLE_TRACK_MM)
    if settings:
        db.settings(**settings)
    rig = Rig(db.update, chassis or Chassis())
    rig.run(5)
    return db, rig


def finish(db, rig, timeout_ms=20_000):
    elapsed = rig.run_until(db.done, timeout_ms)
    rig.run(SETTLE_MS)
    return elapsed


@pytest.mark.parametrize("distance_mm", [1000.0, -1000.0, 37.0])
def test_straight_settles_within_a_millimetre_without_overshoot(distance_mm):
    db, rig = new_rig()
    db.straight(distance_mm)
    finish(db, rig)
    c = rig.chassis
    error_mm = c.x_mm - distance_mm
    direction = math.copysign(1.0, distance_mm)
    overshoot_mm = max(direction * s.x_mm for s in rig.trace) - abs(distance_mm)
    assert abs(error_mm) < 1.0, f"straight({distance_mm}) ended {error_mm:+.3f} mm off"
    assert overshoot_mm < 1.0, f"straight({distance_mm}) overshot by {overshoot_mm:.3f} mm"
    assert abs(c.heading_deg) < 0.2 and abs(c.y_mm) < 1.0, f"veered: {c.heading_deg:.3f} deg, {c.y_mm:.2f} mm"
    distance, speed, _, _ = db.state()
    assert abs(distance - c.x_mm) < 0.5, f"odometry {distance:.2f} mm vs true {c.x_mm:.2f} mm"
    assert rig.trace[-1].duties == (None, None), "then='coast' must release both wheels at the end"


@pytest.mark.parametrize("angle_deg", [90.0, -90.0, 360.0, 3.0])
def test_turn_settles_within_a_fifth_of_a_degree_in_place(angle_deg):
    db, rig = new_rig()
    db.turn(angle_deg)
    finish(db, rig)
    c = rig.chassis
    error_deg = c.heading_deg - angle_deg
    assert abs(error_deg) < 0.2, f"turn({angle_deg}) ended {error_deg:+.3f} deg off"
    assert math.hypot(c.x_mm, c.y_mm) < 1.0, f"turn in place drifted to ({c.x_mm:.2f}, {c.y_mm:.2f}) mm"


def test_positive_turn_is_clockwise_from_above():
    db, rig = new_rig()
    db.turn(30)
    finish(db, rig)
    left, right = rig.chassis.wheels
    assert left.angle_deg > 0 > right.angle_deg, "a right turn drives the left wheel forward"
    assert db.angle() == pytest.approx(30, abs=0.2)


@pytest.mark.parametrize(
    ("radius_mm", "angle_deg"), [(300.0, 90.0), (150.0, -180.0), (-200.0, 90.0), (80.0, 120.0)]
)
def test_curve_traces_a_circle_through_the_ramps(radius_mm, angle_deg):
    db, rig = new_rig()
    db.curve(radius_mm, angle_deg)
    finish(db, rig)
    # A right turn (angle > 0) has its centre on the right of a forward arc, on the left of a backward one.
    side = math.copysign(1.0, angle_deg) * math.copysign(1.0, radius_mm)
    cx, cy = 0.0, -side * abs(radius_mm)
    radial_mm = [math.hypot(s.x_mm - cx, s.y_mm - cy) - abs(radius_mm) for s in rig.trace]
    worst = max(radial_mm, key=abs)
    assert abs(worst) < 1.0, f"curve({radius_mm}, {angle_deg}) strayed {worst:+.3f} mm off its circle"
    c = rig.chassis
    assert c.heading_deg == pytest.approx(angle_deg, abs=0.2)
    # End point: |R| sin|angle| along the travel direction, |R| (1 - cos angle) towards the centre.
    turned = math.radians(abs(angle_deg))
    ex = math.copysign(abs(radius_mm) * math.sin(turned), radius_mm)
    ey = -side * abs(radius_mm) * (1.0 - math.cos(turned))
    assert math.hypot(c.x_mm - ex, c.y_mm - ey) < 1.5, (
        f"ended at ({c.x_mm:.1f}, {c.y_mm:.1f}), not ({ex:.1f}, {ey:.1f})"
    )


def test_curve_caps_the_outer_wheel_at_straight_speed():
    straight_speed = 400.0
    db, rig = new_rig(straight_speed=straight_speed)
    db.curve(200, 180)
    finish(db, rig)
    outer = max(s.speeds_dps[0] for s in rig.trace)
    inner = max(s.speeds_dps[1] for s in rig.trace)
    assert outer <= straight_speed * 1.03, f"outer wheel reached {outer:.0f} deg/s > {straight_speed}"
    assert outer >= straight_speed * 0.97, f"outer wheel only reached {outer:.0f} deg/s"
    expected_ratio = (200 - AXLE_TRACK_MM / 2) / (200 + AXLE_TRACK_MM / 2)
    assert inner / outer == pytest.approx(expected_ratio, rel=0.03)


def test_zero_radius_curve_is_a_turn_in_place():
    db, rig = new_rig()
    db.curve(0, 90)
    finish(db, rig)
    assert rig.chassis.heading_deg == pytest.approx(90, abs=0.2)
    assert math.hypot(rig.chassis.x_mm, rig.chassis.y_mm) < 1.0


def chassis_speed_mm_s(sample):
    return 0.5 * (sample.speeds_dps[0] + sample.speeds_dps[1]) * MM_PER_WHEEL_DEG


def test_then_continue_carries_cruise_speed_into_the_next_segment():
    cruise_dps = 400.0
    cruise_mm_s = cruise_dps * MM_PER_WHEEL_DEG
    db, rig = new_rig(straight_speed=cruise_dps)
    db.straight(300, then="continue")
    rig.run_until(db.done, 5000)
    seam = len(rig.trace)
    at_seam = chassis_speed_mm_s(rig.trace[-1])
    assert rig.chassis.x_mm == pytest.approx(300, abs=2), "continue must report done at the segment's end"
    assert at_seam == pytest.approx(cruise_mm_s, rel=0.03), f"{at_seam:.0f} mm/s at the seam"
    rig.run(100)  # the user program takes its time to issue the next segment: the robot keeps cruising
    assert chassis_speed_mm_s(rig.trace[-1]) == pytest.approx(cruise_mm_s, rel=0.03)
    db.straight(300)
    finish(db, rig)
    # The second segment starts at cruise: no dip between the seam and its own deceleration.
    second_cruise = [chassis_speed_mm_s(s) for s in rig.trace[seam : seam + 300]]
    assert min(second_cruise) > 0.95 * cruise_mm_s, f"speed dipped to {min(second_cruise):.0f} mm/s"
    travelled = rig.chassis.x_mm
    assert travelled == pytest.approx(300 + 100 * cruise_mm_s / 1000 + 300, abs=1.0)


def test_continue_chain_straight_curve_straight_flows_without_stopping():
    db, rig = new_rig(straight_speed=400)
    db.straight(200, then="continue")
    rig.run_until(db.done, 5000)
    start = len(rig.trace)
    db.curve(250, 90, then="continue")
    rig.run_until(db.done, 5000)
    db.straight(200)
    finish(db, rig)
    between = [chassis_speed_mm_s(s) for s in rig.trace[start:] if s.t_ms < rig.trace[-SETTLE_MS].t_ms - 400]
    centre_mm_s = 400 * MM_PER_WHEEL_DEG * 250 / (250 + AXLE_TRACK_MM / 2)
    assert min(between) > 0.9 * centre_mm_s, f"dipped to {min(between):.0f} mm/s between segments"
    assert rig.chassis.heading_deg == pytest.approx(90, abs=0.3)


def test_short_move_armed_at_speed_lands_on_target_by_braking_harder():
    db, rig = new_rig(straight_speed=600)
    db.drive(600 * MM_PER_WHEEL_DEG, 0)
    rig.run_until(db.done, 3000)
    rig.run(200)
    x0 = rig.chassis.x_mm
    db.straight(20)  # far shorter than the ~40 mm the configured deceleration needs from 600 deg/s
    finish(db, rig)
    travelled = rig.chassis.x_mm - x0
    overshoot = max(s.x_mm for s in rig.trace) - x0 - 20
    assert travelled == pytest.approx(20, abs=1.5), f"travelled {travelled:.2f} mm for straight(20)"
    assert overshoot < 1.5, f"overshot by {overshoot:.2f} mm"


def wheel_accelerations(trace, window_ms=20):
    """Each wheel's acceleration over a sliding window, deg/s^2 (the window averages out duty jitter)."""
    return [
        max(abs(b.speeds_dps[i] - a.speeds_dps[i]) for i in (0, 1)) * 1000.0 / window_ms
        for a, b in zip(trace, trace[window_ms:], strict=False)
    ]


def test_drive_ramps_both_wheels_together_keeping_the_arc_radius():
    db, rig = new_rig(acceleration=1000)
    speed_mm_s, rate_dps = 150.0, 60.0
    db.drive(speed_mm_s, rate_dps)
    elapsed = rig.run_until(db.done, 3000)
    rig.run(300)
    radius_mm = speed_mm_s / math.radians(rate_dps)
    outer_dps = (speed_mm_s + math.radians(rate_dps) * AXLE_TRACK_MM / 2) / MM_PER_WHEEL_DEG
    assert elapsed / 1000 == pytest.approx(outer_dps / 1000, abs=0.01), "ramp time set by the faster wheel"
    mid = rig.trace[elapsed // 2 + 5]
    left, right = mid.speeds_dps
    ratio = right / left
    expected = (radius_mm - AXLE_TRACK_MM / 2) / (radius_mm + AXLE_TRACK_MM / 2)
    assert ratio == pytest.approx(expected, rel=0.05), "mid-ramp wheel speeds must keep the arc's ratio"
    assert rig.trace[-1].speeds_dps[0] == pytest.approx(outer_dps, rel=0.03)
    peak = max(wheel_accelerations(rig.trace[20 : elapsed - 20]))
    assert peak < 1000 * 1.25, f"a wheel accelerated at {peak:.0f} deg/s^2 with acceleration=1000"


def test_move_wheels_reaches_each_wheel_speed():
    db, rig = new_rig()
    db.move_wheels(300, -150)
    rig.run_until(db.done, 3000)
    rig.run(300)
    left, right = rig.trace[-1].speeds_dps
    assert left == pytest.approx(300, rel=0.03) and right == pytest.approx(-150, rel=0.03)


def test_a_blocked_robot_waits_and_then_lands_on_target_without_a_lunge():
    """A robot held against an obstacle mid-move, then released.

    The reference waits while the robot cannot follow (it does not run on towards the target), and on
    release the rest of the move is re-planned from where the robot is, under the acceleration limit:
    no catching up at full duty, no overshoot.
    """
    db, rig = new_rig()
    db.straight(300)
    rig.run(900)
    for wheel in rig.chassis.wheels:
        wheel.blocked = True
    rig.run(1000)
    assert not db.done(), "a blocked robot must not report done()"
    x_blocked = rig.chassis.x_mm
    pushing = rig.trace[-1].duties
    assert all(d is not None and d > 20 for d in pushing), f"it should keep pushing forward: {pushing}"
    for wheel in rig.chassis.wheels:
        wheel.blocked = False
    released = len(rig.trace)
    finish(db, rig)
    c = rig.chassis
    overshoot = max(s.x_mm for s in rig.trace) - 300
    assert abs(c.x_mm - 300) < 1.0, f"ended {c.x_mm - 300:+.2f} mm off after the block"
    assert overshoot < 1.0, f"overshot by {overshoot:.2f} mm"
    peak_dps = max(max(s.speeds_dps) for s in rig.trace[released:])
    assert peak_dps < 360 * 1.1, f"after release a wheel raced to {peak_dps:.0f} deg/s (straight_speed 360)"
    settle_accel = max(wheel_accelerations(rig.trace[released + 40 :]))
    # The landing plans at 1500 deg/s^2; following it after the release transient costs up to ~30 % more.
    assert settle_accel < 1500 * 1.5, f"the landing accelerated a wheel at {settle_accel:.0f} deg/s^2"
    assert x_blocked < 300 - 50, "the block should have come well before the target"
