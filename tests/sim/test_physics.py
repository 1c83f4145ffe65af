"""The robot on the floor: pose conventions, which way the wheels roll, and odometry against travel."""

import math

import pytest

import openbricks_native as native
from openbricks_sim.physics import ControlBusyError, Physics


@pytest.fixture
def physics():
    p = Physics("empty", "st3032")
    yield p
    p.close()


def wheel_distance_mm(physics, before, after):
    """Travel of the axle centre that the wheel angles account for (what a drivebase's odometry sees)."""
    turned = ((after[0] - before[0]) + (after[1] - before[1])) / 2
    return turned / 360.0 * math.pi * physics.chassis.wheel_diameter_mm


def test_the_robot_starts_settled_at_the_pose_it_was_given():
    p = Physics("empty", "st3032", start_mm_deg=(120.0, -40.0, 30.0))
    try:
        pose = p.pose()
        assert pose.x_mm == pytest.approx(120.0, abs=0.1)
        assert pose.y_mm == pytest.approx(-40.0, abs=0.1)
        assert pose.heading_deg == pytest.approx(30.0, abs=0.01)
        assert p.now_ms == 0
        axle_mm = p.data.qpos[2] * 1000
        assert axle_mm == pytest.approx(p.chassis.wheel_diameter_mm / 2, abs=0.05), "resting on its wheels"
    finally:
        p.close()


def test_positive_duty_rolls_forward_on_both_sides_and_the_left_wheel_alone_turns_right(physics):
    physics.attach_control()
    left, right = physics.wheel_io(0), physics.wheel_io(1)
    left.write_duty(40)
    right.write_duty(40)
    physics.step(500)
    pose = physics.pose()
    assert pose.x_mm > 50 and abs(pose.y_mm) < 1 and abs(pose.heading_deg) < 0.5
    right.coast()
    physics.step(500)
    assert physics.pose().heading_deg > 10, "left wheel driving alone turns the robot clockwise (right)"


def test_odometry_matches_travel_within_a_tenth_of_a_percent_on_a_slow_straight_drive(physics):
    world = native.MotorProcess()
    physics.attach_control(world)
    servos = [native.Servo(io=physics.wheel_io(i)) for i in (0, 1)]
    for servo in servos:
        world.subscribe(servo)
        servo.run_speed(90.0)  # about 69 mm/s on 88 mm wheels
    physics.step(300)  # past the ramp
    before = [physics.wheel_angle_deg(0), physics.wheel_angle_deg(1)]
    x0 = physics.pose().x_mm
    physics.step(8000)
    travel = physics.pose().x_mm - x0
    odometry = wheel_distance_mm(physics, before, [physics.wheel_angle_deg(0), physics.wheel_angle_deg(1)])
    assert travel > 500
    assert abs(travel - odometry) / travel < 0.001, f"travel {travel:.3f} mm vs odometry {odometry:.3f} mm"


def test_a_coasting_robot_stops_within_a_few_centimetres(physics):
    physics.attach_control()
    ios = [physics.wheel_io(i) for i in (0, 1)]
    for io in ios:
        io.write_duty(60)
    physics.step(1000)
    for io in ios:
        io.coast()
    x0 = physics.pose().x_mm
    physics.step(1000)
    rolled = physics.pose().x_mm - x0
    assert 0 < rolled < 40, f"rolled {rolled:.1f} mm after coasting: the servo gearbox should stop it"
    assert abs(ios[0].speed_dps) < 1


def test_only_one_robot_per_process_holds_the_control_callback(physics):
    physics.attach_control()
    other = Physics("empty", "st3032")
    try:
        with pytest.raises(ControlBusyError, match="process-wide"):
            other.attach_control()
        physics.close()
        other.attach_control()  # free once the first one let go
    finally:
        other.close()


def test_jgb37_chassis_uses_its_own_wheels_and_encoder():
    p = Physics("empty", "jgb37")
    try:
        p.attach_control()
        io = p.wheel_io(0)
        io.write_duty(100)
        p.step(1000)
        # The 1:30 motor spins much faster than the servo: near its 1998 deg/s no-load speed, less the
        # robot's rolling load.
        assert 1500 < io.speed_dps < 2000
        assert p.chassis.wheel_diameter_mm == 65.0
    finally:
        p.close()


def test_bare_steps_without_control_leave_the_motors_off(physics):
    physics.step(100)
    assert physics.now_ms == 100
    assert physics.data.ctrl[0] == 0.0 and abs(physics.pose().x_mm) < 0.01
