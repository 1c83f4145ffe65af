"""DriveBase on two JGB37-520 encoder motors: the native controller against DC-motor plants on the fake
board, judged by where the chassis really went."""

import time

from fakes.expect import approx, raises
from openbricks import estop
from openbricks.parameters import Stop
from tests.openbricks.robotics.robots import EncoderRobot

NEEDS_NATIVE = True


def _elapsed_ms(since):
    return time.ticks_diff(time.ticks_ms(), since)


def test_straight_drives_the_distance_and_keeps_the_heading():
    robot = EncoderRobot()
    db = robot.drivebase()
    start = time.ticks_ms()
    db.straight(400)
    chassis = robot.chassis
    assert approx(chassis.x_mm, 400, 2)
    assert approx(chassis.y_mm, 0, 2)
    assert approx(chassis.heading_deg, 0, 0.5)
    assert approx(db.distance(), 400, 1)
    # 705 wheel-deg at the default 360 deg/s, with 1500 deg/s^2 ramps: about 2.2 s.
    assert 1900 < _elapsed_ms(start) < 3000


def test_negative_distance_drives_backward():
    robot = EncoderRobot()
    robot.drivebase().straight(-150)
    assert approx(robot.chassis.x_mm, -150, 2)


def test_positive_turn_is_clockwise_from_above_and_stays_on_the_spot():
    robot = EncoderRobot()
    db = robot.drivebase()
    db.turn(90)
    chassis = robot.chassis
    assert approx(chassis.heading_deg, 90, 1)
    assert approx(chassis.x_mm, 0, 1) and approx(chassis.y_mm, 0, 1)
    assert approx(db.angle(), 90, 0.5)
    db.turn(-180)
    assert approx(chassis.heading_deg, -90, 1)


def test_curve_sweeps_a_quarter_circle_around_a_centre_to_the_right():
    robot = EncoderRobot()
    robot.drivebase().curve(200, 90)
    chassis = robot.chassis
    # Centre 200 mm to the right (y = -200): a right quarter circle ends at (200, -200) facing right.
    assert approx(chassis.x_mm, 200, 4)
    assert approx(chassis.y_mm, -200, 4)
    assert approx(chassis.heading_deg, 90, 1.5)


def test_curve_with_a_negative_radius_drives_the_arc_backward():
    robot = EncoderRobot()
    robot.drivebase().curve(radius=-200, angle=-90)
    chassis = robot.chassis
    assert approx(chassis.x_mm, -200, 4)
    assert approx(chassis.y_mm, -200, 4)
    assert approx(chassis.heading_deg, -90, 1.5)


def test_curve_keeps_the_outer_wheel_at_the_straight_speed():
    robot = EncoderRobot()
    db = robot.drivebase()
    db.settings(straight_speed=300)
    db.curve(100, 180, wait=False)
    fastest = 0.0
    while not db.done():
        time.sleep_ms(10)
        fastest = max(fastest, max(abs(s) for s in robot.wheel_speeds_dps()))
    assert 280 < fastest < 320


def test_then_coast_releases_both_bridges_and_then_hold_resists_a_push():
    robot = EncoderRobot()
    db = robot.drivebase()
    db.straight(100)
    time.sleep_ms(20)
    assert robot.bridge_duties() == (None, None)
    db.straight(100, then=Stop.HOLD)
    held_at = robot.plants[0].angle_deg
    robot.plants[0].load_torque_nm = 0.05  # a hand pushing the left wheel
    time.sleep_ms(300)
    robot.plants[0].load_torque_nm = 0.0
    time.sleep_ms(500)
    assert approx(robot.plants[0].angle_deg, held_at, 2)
    assert robot.bridge_duties()[0] is not None


def test_then_brake_shorts_both_windings_at_rest():
    robot = EncoderRobot()
    db = robot.drivebase()
    db.straight(100, then="brake")
    time.sleep_ms(20)
    assert robot.bridge_duties() == (0.0, 0.0)


def test_then_continue_ends_at_cruise_speed_and_keeps_it():
    robot = EncoderRobot()
    db = robot.drivebase()
    db.settings(straight_speed=300)
    db.straight(200, then="continue")
    left, right = robot.wheel_speeds_dps()
    assert approx(left, 300, 20) and approx(right, 300, 20)
    time.sleep_ms(300)
    left, right = robot.wheel_speeds_dps()
    assert approx(left, 300, 20) and approx(right, 300, 20)
    db.straight(100)  # the next segment picks the speed up and decelerates to rest
    assert approx(robot.chassis.x_mm, 300 + 300 * 0.3 * 3.14159 * 65 / 360, 4)


def test_an_unknown_end_state_is_refused_before_anything_moves():
    robot = EncoderRobot()
    db = robot.drivebase()
    with raises(ValueError, "then='float' is not an end state"):
        db.straight(100, then="float")
    time.sleep_ms(50)
    assert robot.chassis.x_mm == 0


def test_wait_false_returns_at_once_and_done_reports_arrival():
    robot = EncoderRobot()
    db = robot.drivebase()
    start = time.ticks_ms()
    db.straight(300, wait=False)
    assert _elapsed_ms(start) < 5
    assert not db.done()
    polls = 0
    while not db.done():
        time.sleep_ms(10)
        polls += 1
    assert polls > 100
    assert approx(robot.chassis.x_mm, 300, 2)


def test_a_new_move_supersedes_a_pending_one():
    robot = EncoderRobot()
    db = robot.drivebase()
    db.straight(1000, wait=False)
    time.sleep_ms(500)
    db.turn(90)
    assert approx(robot.chassis.heading_deg, 90, 2)
    assert robot.chassis.x_mm < 400  # the straight was abandoned, well short of 1000 mm


def test_stop_coasts_both_wheels_and_returns_at_once():
    robot = EncoderRobot()
    db = robot.drivebase()
    db.drive(200, 0)
    time.sleep_ms(500)
    start = time.ticks_ms()
    db.stop()
    assert _elapsed_ms(start) < 5
    time.sleep_ms(1)
    assert robot.bridge_duties() == (None, None)
    assert db.done()


def test_stop_brake_with_wait_blocks_until_the_wheels_are_at_rest():
    robot = EncoderRobot()
    db = robot.drivebase()
    db.drive(250, 0)
    time.sleep_ms(800)
    start = time.ticks_ms()
    db.stop(then="brake", wait=True)
    # 450 wheel-deg/s at 1500 deg/s^2 takes 0.3 s to ramp down.
    assert 250 < _elapsed_ms(start) < 700
    left, right = robot.wheel_speeds_dps()
    assert abs(left) < 5 and abs(right) < 5
    x = robot.chassis.x_mm
    time.sleep_ms(200)
    assert approx(robot.chassis.x_mm, x, 0.5)


def test_stop_wait_raises_naming_the_speeds_when_the_robot_keeps_rolling():
    robot = EncoderRobot()
    db = robot.drivebase()
    for plant in robot.plants:
        plant.load_torque_nm = 0.02  # downhill: both wheels keep turning while they coast
    robot.plants[1].load_torque_nm = -0.02  # the mirrored motor turns the other way for "forward"
    time.sleep_ms(300)
    with raises(RuntimeError, "still moving 5000 ms after the stop") as caught:
        db.stop(wait=True)
    assert "left" in str(caught.value) and "wheel-deg/s" in str(caught.value)


def test_drive_ramps_to_the_speed_and_turn_rate_and_holds_them():
    robot = EncoderRobot()
    db = robot.drivebase()
    db.drive(150, 30)
    time.sleep_ms(1500)
    _distance, speed_mm_s, _angle, rate_dps = db.state()
    assert approx(speed_mm_s, 150, 5)
    assert approx(rate_dps, 30, 2)
    before = robot.chassis.heading_deg
    time.sleep_ms(1000)
    assert approx(robot.chassis.heading_deg - before, 30, 2)
    db.stop()


def test_move_wheels_runs_each_wheel_at_its_own_speed():
    robot = EncoderRobot()
    db = robot.drivebase()
    db.move_wheels(200, 120)
    time.sleep_ms(800)
    left, right = robot.wheel_speeds_dps()
    assert approx(left, 200, 8) and approx(right, 120, 8)
    assert robot.chassis.heading_deg > 5  # the faster left wheel turns the robot right
    db.move_wheels(200, -200)
    time.sleep_ms(800)
    left, right = robot.wheel_speeds_dps()
    assert approx(left, 200, 8) and approx(right, -200, 8)
    db.stop()


def test_settings_defaults_and_units():
    robot = EncoderRobot()
    db = robot.drivebase()
    assert db.settings() == (360.0, 360.0, 1500.0, 1500.0)
    db.settings(straight_speed=180, acceleration=900)
    assert db.settings() == (180.0, 360.0, 900.0, 900.0)  # on encoder motors turns ramp at `acceleration`
    start = time.ticks_ms()
    db.straight(300)
    # 529 wheel-deg at 180 wheel-deg/s: about 3 s plus the ramps (not 1.5 s as at the default speed).
    assert _elapsed_ms(start) > 3000
    assert approx(robot.chassis.x_mm, 300, 2)


def test_settings_refuses_bad_values_and_turn_acceleration_on_encoder_motors():
    robot = EncoderRobot()
    db = robot.drivebase()
    with raises(ValueError, "settings(straight_speed=0): give a positive number in wheel-deg/s"):
        db.settings(straight_speed=0)
    with raises(ValueError, "wheel-deg/s^2"):
        db.settings(acceleration=-5)
    with raises(ValueError, "applies to serial-bus drive bases"):
        db.settings(turn_acceleration=800)
    assert db.settings() == (360.0, 360.0, 1500.0, 1500.0)


def test_reset_makes_the_current_pose_zero_and_is_refused_during_a_move():
    robot = EncoderRobot()
    db = robot.drivebase()
    db.straight(100)
    db.turn(-90)
    db.reset()
    assert db.distance() == 0 and db.angle() == 0
    db.straight(130)
    assert approx(db.distance(), 130, 1)
    assert approx(robot.chassis.y_mm, 130, 3)  # along the new zero: to the robot's left at the start
    db.straight(200, wait=False)
    with raises(RuntimeError, "a move is in progress"):
        db.reset()


def test_use_gyro_needs_an_imu():
    robot = EncoderRobot()
    db = robot.drivebase()
    with raises(ValueError, "use_gyro(True) needs an IMU"):
        db.use_gyro(True)


def test_estop_releases_the_wheels_mid_move_and_refuses_the_next_command():
    robot = EncoderRobot()
    db = robot.drivebase()
    db.straight(500, wait=False)
    time.sleep_ms(300)
    estop.engage("test")
    time.sleep_ms(1)
    assert robot.bridge_duties() == (None, None)
    with raises(estop.EStopError, "DriveBase.straight refused"):
        db.straight(100)


def test_a_blocking_move_raises_when_the_robot_is_stuck():
    robot = EncoderRobot()
    db = robot.drivebase()
    for plant in robot.plants:
        plant.blocked = True  # driven into a wall
    with raises(RuntimeError, "is stuck"):
        db.straight(300)
    time.sleep_ms(1)
    assert robot.bridge_duties() == (None, None)


def test_check_motors_has_nothing_to_check_on_encoder_motors():
    robot = EncoderRobot()
    robot.drivebase().check_motors()


def test_the_drive_base_takes_the_bridges_from_the_motors_own_controllers():
    import _openbricks_native

    robot = EncoderRobot()
    robot.left.run_speed(100)  # the motor's own servo core drives its bridge ...
    db = robot.drivebase()
    db.straight(100)  # ... until the drive base takes both bridges
    assert not _openbricks_native.motor_process.is_subscribed(robot.left._servo)
    assert approx(robot.chassis.x_mm, 100, 2)


def test_close_releases_the_wheels_and_leaves_the_motors_to_their_own_controllers():
    import _openbricks_native

    robot = EncoderRobot()
    db = robot.drivebase()
    db.drive(150, 0)
    time.sleep_ms(300)
    db.close()
    time.sleep_ms(1)
    assert robot.bridge_duties() == (None, None)
    assert _openbricks_native.motor_process.count == 0
    time.sleep_ms(500)  # let the coasting wheel roll to a stop
    start = robot.left.angle()
    robot.left.run_angle(300, 90)  # the motor's own servo core drives it again
    assert approx(robot.left.angle() - start, 90, 2)


def test_a_second_drive_base_over_the_same_motors_takes_them_from_the_first():
    import _openbricks_native

    robot = EncoderRobot()
    first = robot.drivebase()
    first.drive(150, 0)
    time.sleep_ms(300)
    second = robot.drivebase()
    second.straight(100)
    assert _openbricks_native.motor_process.count == 1  # only the second one drives
    assert first.done()  # the first one's drive() was ended, not left fighting
    x = robot.chassis.x_mm
    time.sleep_ms(300)
    assert approx(robot.chassis.x_mm, x, 1)


def test_a_direct_command_takes_the_wheel_back_and_the_next_move_retakes_both():
    import _openbricks_native

    robot = EncoderRobot()
    db = robot.drivebase()
    db.straight(1000, then="hold", wait=False)
    time.sleep_ms(500)
    robot.left.run_speed(200)  # Pybricks: using a drive base motor directly stops the drive base
    assert db.done()  # the move was ended, not left pending
    time.sleep_ms(700)
    since_ms = time.ticks_ms()
    time.sleep_ms(300)
    # One driver per bridge: the left duty follows its own speed loop alone, steady at cruise (a drive
    # base still holding would pull it the other way every tick) and nothing drives the right bridge.
    duties = [duty for at_ms, duty in robot.rigs[0].duty_log if at_ms >= since_ms]
    duties.append(robot.bridge_duties()[0])
    assert min(duties) > 0 and max(duties) - min(duties) < 5
    assert approx(robot.wheel_speeds_dps()[0], 200, 8)
    assert robot.bridge_duties()[1] is None
    assert _openbricks_native.motor_process.count == 1
    db.straight(100)  # the drive base takes both bridges back: the left's speed loop stands down
    travel, heading = robot.chassis.travel_mm, robot.chassis.heading_deg
    db.straight(100)
    assert approx(robot.chassis.travel_mm - travel, 100, 2)
    assert approx(robot.chassis.heading_deg, heading, 1)
    assert _openbricks_native.motor_process.count == 1


def test_reading_a_wheel_leaves_the_drive_base_driving_it():
    robot = EncoderRobot()
    robot.left.run_speed(-100)  # the motor's own core had a command of its own before the drive base
    db = robot.drivebase()
    db.drive(150, 0)
    time.sleep_ms(600)
    robot.left.speed()
    robot.left.stalled()
    robot.left.angle()
    time.sleep_ms(600)
    _distance, speed_mm_s, _angle, _rate = db.state()
    assert approx(speed_mm_s, 150, 5)
    assert approx(robot.wheel_speeds_dps()[0], robot.wheel_speeds_dps()[1], 5)
    db.stop()


def test_a_stop_on_a_drive_base_wheel_is_allowed_during_an_estop_and_motion_is_refused():
    robot = EncoderRobot()
    db = robot.drivebase()
    db.drive(150, 0)
    time.sleep_ms(300)
    estop.engage("test")
    robot.left.brake()  # stops are always allowed, as on a motor no drive base drives
    time.sleep_ms(2)
    assert robot.bridge_duties()[0] == 0.0
    with raises(estop.EStopError, "JGB37Motor run_speed() refused"):
        robot.left.run_speed(100)
    with raises(estop.EStopError, "DriveBase.straight refused"):
        db.straight(100)
