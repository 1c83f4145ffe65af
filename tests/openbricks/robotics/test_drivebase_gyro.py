"""DriveBase steering by a gyro: the fake ICM-45686 sees the chassis' real rotation, wheel slip and all."""

import time

from fakes.expect import approx, raises
from tests.openbricks.robotics.robots import EncoderRobot

NEEDS_NATIVE = True


def test_the_gyro_steers_out_the_heading_error_a_slipping_wheel_gives_the_encoders():
    slip = (0.05, 0.0)  # the left tyre loses 5 % of its rotation to the floor
    robot = EncoderRobot(gyro=True, slip=slip)
    robot.drivebase().straight(500)
    encoders_only = robot.chassis.heading_deg
    robot.close()

    robot = EncoderRobot(gyro=True, slip=slip)
    db = robot.drivebase()
    db.use_gyro(True)
    db.straight(500)
    assert encoders_only < -5  # the left wheel lagged on the floor: veered left
    assert approx(robot.chassis.heading_deg, 0, 1)


def test_gyro_turns_land_on_the_measured_heading():
    robot = EncoderRobot(gyro=True, slip=(0.08, 0.08))
    db = robot.drivebase()
    db.use_gyro(True)
    db.turn(90)
    assert approx(robot.chassis.heading_deg, 90, 1)
    assert approx(db.angle(), 90, 0.5)


def test_imu_reset_heading_is_refused_while_the_drive_base_steers_by_it():
    robot = EncoderRobot(gyro=True)
    db = robot.drivebase()
    db.use_gyro(True)
    with raises(OSError, "can't reset heading while gyro in use"):
        robot.imu.reset_heading()
    db.use_gyro(False)
    robot.imu.reset_heading()  # encoders steer now: the IMU's frame is free again


def test_reset_zeroes_the_drive_base_and_the_imu_together_and_the_next_move_follows_the_new_zero():
    robot = EncoderRobot(gyro=True)
    db = robot.drivebase()
    db.use_gyro(True)
    db.straight(100)
    db.turn(-90)
    db.reset()
    assert db.angle() == 0 and db.distance() == 0
    assert approx(robot.imu.heading(), 0, 0.05)
    time.sleep_ms(50)
    assert approx(db.angle(), 0, 0.3)  # the held heading did not jump when the frames moved
    db.straight(130)
    chassis = robot.chassis
    assert approx(chassis.heading_deg, -90, 1)
    assert approx(chassis.x_mm, 100, 3) and approx(chassis.y_mm, 130, 3)
    assert robot.imu.heading_locked_by() is db  # still steering by the gyro


def test_reset_is_refused_while_a_gyro_move_is_in_progress_and_changes_nothing():
    robot = EncoderRobot(gyro=True)
    db = robot.drivebase()
    db.use_gyro(True)
    db.turn(45, wait=False)
    time.sleep_ms(100)
    with raises(RuntimeError, "a move is in progress"):
        db.reset()
    while not db.done():
        time.sleep_ms(10)
    assert approx(robot.chassis.heading_deg, 45, 1)


class WrappingCompass:
    """A heading source that wraps to [-180, 180) like a BNO055, fed by the chassis."""

    def __init__(self, chassis):
        self.chassis = chassis

    def heading(self):
        return (self.chassis.heading_deg + 180.0) % 360.0 - 180.0

    def reset_heading(self, angle=0):
        raise AssertionError("not used here")


def test_a_wrapping_heading_source_is_followed_across_180_degrees():
    robot = EncoderRobot()
    from openbricks.robotics import DriveBase

    db = DriveBase(robot.left, robot.right, 65, 150, imu=WrappingCompass(robot.chassis))
    db.use_gyro(True)
    db.turn(150)
    db.turn(60)  # through +180, where the compass jumps to -180
    assert approx(robot.chassis.heading_deg, 210, 1.5)
