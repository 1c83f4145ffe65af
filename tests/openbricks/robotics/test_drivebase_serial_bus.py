"""DriveBase on two ST-3032 serial-bus servos: adopted onto a bus engine that speaks SCS to the fake servos.

The engine is the firmware's C engine (`_openbricks_native.serial_bus`), here over the fake board's
UART: it owns the UART after the hand-over, drives each servo in open-loop duty mode on the tick and
counts the reads that went unanswered.
"""

import sys
import time

import _openbricks_native
import machine

from fakes.expect import approx, raises
from fakes.scs_servo import FakeServo, ScsBus, scs
from openbricks import estop
from tests.openbricks.robotics.robots import SERVO_TRACK_MM, SERVO_WHEEL_MM, ServoRobot, clean_slate

NEEDS_NATIVE = True

MM_PER_WHEEL_DEG = 3.141592653589793 * SERVO_WHEEL_MM / 360


def test_construction_hands_the_uart_to_the_engine_and_adopts_both_wheels():
    robot = ServoRobot()
    robot.drivebase()
    assert robot.left.bus.handed_over
    assert (robot.left.slot, robot.right.slot) == (0, 1)
    assert (robot.left.side, robot.right.side) == ("left wheel", "right wheel")
    assert [servo.mode for servo in robot.servos] == [2, 2]  # open-loop duty: the engine closes the loop


def test_straight_and_turn_through_the_engine_land_on_target():
    robot = ServoRobot()
    db = robot.drivebase()
    db.straight(300)
    chassis = robot.chassis
    assert approx(chassis.x_mm, 300, 2)
    assert approx(chassis.heading_deg, 0, 0.5)
    # The mirror-mounted right servo turned its own shaft backward for the same travel.
    assert approx(robot.servos[1].angle_deg(), -300 / MM_PER_WHEEL_DEG, 3)
    db.turn(90)
    assert approx(chassis.heading_deg, 90, 1)


def test_a_300_mm_square_closes_within_10_mm_and_2_degrees_as_in_the_simulator():
    robot = ServoRobot()
    db = robot.drivebase()
    chassis = robot.chassis
    for _ in range(4):
        db.straight(300)
        db.turn(90)
    gap = (chassis.x_mm**2 + chassis.y_mm**2) ** 0.5
    heading_error = (chassis.heading_deg + 180) % 360 - 180
    print("square: gap %.2f mm, heading error %.2f deg" % (gap, heading_error))
    assert gap < 10.0, "the square opened by %.1f mm" % gap
    assert abs(heading_error) < 2.0
    # Every wheel read on the tick was answered: 1 kHz feedback over the 1 Mbaud bus.
    for slot in (0, 1):
        replies, failed, _ = robot.engine().stats(slot)
        assert failed == 0 and replies > 4000


def test_a_wheel_that_goes_silent_mid_drive_raises_naming_it_within_50_ms():
    robot = ServoRobot()
    db = robot.drivebase()
    db.drive(150, 0)
    time.sleep_ms(300)
    robot.servos[0].silent = True
    silent_at = time.ticks_ms()
    with raises(OSError, "not responding on the bus: left wheel (servo id 1, slot 0)"):
        for _ in range(100):
            db.check_motors()
            time.sleep_ms(1)
    assert time.ticks_diff(time.ticks_ms(), silent_at) <= 50


def test_stop_coast_cuts_the_torque_of_both_servos():
    robot = ServoRobot()
    db = robot.drivebase()
    db.drive(150, 0)
    time.sleep_ms(400)
    db.stop()
    time.sleep_ms(2)
    assert [servo.reg16(scs.REG_TORQUE_ENABLE) & 0xFF for servo in robot.servos] == [0, 0]


def test_stop_hold_with_wait_blocks_until_the_robot_is_at_rest():
    robot = ServoRobot()
    db = robot.drivebase()
    db.drive(200, 0)
    time.sleep_ms(600)
    db.stop(then="hold", wait=True)
    assert abs(robot.servos[0].speed_dps()) < 5 and abs(robot.servos[1].speed_dps()) < 5
    x = robot.chassis.x_mm
    time.sleep_ms(300)
    assert approx(robot.chassis.x_mm, x, 0.5)


def test_move_wheels_sets_both_wheel_speeds():
    robot = ServoRobot()
    db = robot.drivebase()
    db.move_wheels(200, 120)
    time.sleep_ms(800)
    assert approx(robot.servos[0].speed_dps(), 200, 10)
    assert approx(-robot.servos[1].speed_dps(), 120, 10)
    db.stop()


def test_settings_turn_acceleration_shapes_only_the_turns():
    robot = ServoRobot()
    db = robot.drivebase()
    db.settings(turn_acceleration=300)
    assert db.settings() == (360.0, 360.0, 1500.0, 300.0)
    start = time.ticks_ms()
    db.turn(90)
    slow_turn_ms = time.ticks_diff(time.ticks_ms(), start)
    db.settings(turn_acceleration=1500)
    start = time.ticks_ms()
    db.turn(90)
    assert time.ticks_diff(time.ticks_ms(), start) < slow_turn_ms - 300


def test_a_silent_servo_at_construction_raises_naming_side_id_uart_and_pins():
    robot = ServoRobot(silent_ids=(2,))
    with raises(OSError, "motor is not responding on the bus: right wheel (servo id 2)") as caught:
        robot.drivebase()
    message = str(caught.value)
    assert "on UART1 tx=14 rx=41" in message
    assert "`openbricks servo-id --scan`" in message
    assert not robot.left.bus.handed_over  # found before the UART changed hands


def test_a_wheel_going_silent_mid_move_halts_both_and_raises_naming_the_motor():
    robot = ServoRobot()
    db = robot.drivebase()
    db.straight(500, wait=False)
    time.sleep_ms(400)
    robot.servos[0].silent = True  # the left wheel's cable works loose
    with raises(
        OSError, "motor is not responding on the bus: left wheel (servo id 1, slot 0) on UART1"
    ) as caught:
        while not db.done():
            time.sleep_ms(10)
    assert "failed reads" in str(caught.value)
    # Halted at once: the right wheel was released rather than driven on alone.
    assert robot.servos[1].reg16(scs.REG_TORQUE_ENABLE) & 0xFF == 0
    assert robot.chassis.x_mm < 300


def test_check_motors_raises_once_a_wheel_stops_answering_and_moves_refuse():
    robot = ServoRobot()
    db = robot.drivebase()
    db.check_motors()
    robot.servos[1].silent = True
    time.sleep_ms(3)  # the engine reads every wheel each tick; three misses in a row make it silent
    with raises(OSError, "right wheel (servo id 2, slot 1) on UART1 tx=14 rx=41"):
        db.check_motors()
    with raises(OSError, "not responding on the bus: right wheel"):
        db.straight(100)
    robot.servos[1].silent = False
    time.sleep_ms(2)  # the next tick's read hears it again
    db.straight(100)  # answering again: moves work again
    assert approx(robot.chassis.x_mm, 100, 2)


class _CoresWithoutTheEngine:
    """`_openbricks_native` as a build without the bus engine has it (no serial_bus)."""


def test_without_a_bus_engine_construction_raises_instead_of_degrading():
    robot = ServoRobot()
    sys.modules["_openbricks_native"] = _CoresWithoutTheEngine()
    try:
        with raises(RuntimeError, "needs the native bus engine") as caught:
            robot.drivebase()
    finally:
        sys.modules["_openbricks_native"] = _openbricks_native
    assert "ST3032Motor (servo id 1 on UART1 tx=14 rx=41)" in str(caught.value)
    assert not robot.left.bus.handed_over
    robot.left.run_speed(100)  # the motors still work on their own bus


def test_adopted_motors_keep_their_motor_api_and_take_their_wheel_from_the_drive_base():
    robot = ServoRobot()
    db = robot.drivebase()
    db.straight(100)
    assert approx(robot.left.angle(), 100 / MM_PER_WHEEL_DEG, 2)
    robot.left.reset_angle(0)
    robot.left.run_angle(300, 180)  # a direct command: the drive base lets go of its wheels
    assert approx(robot.left.angle(), 180, 2)
    assert approx(robot.servos[0].angle_deg(), 100 / MM_PER_WHEEL_DEG + 180, 3)
    robot.right.run_speed(90)
    time.sleep_ms(600)
    assert approx(robot.right.speed(), 90, 8)
    assert approx(robot.servos[1].speed_dps(), -90, 8)  # in the motor's own (inverted) frame
    db.stop()  # the drive base takes both wheels back: the right one's own speed loop stands down
    time.sleep_ms(300)
    heading, travel = robot.chassis.heading_deg, robot.chassis.travel_mm
    assert abs(robot.servos[1].speed_dps()) < 1
    # One driver for both wheels, the drive base, after the bus engine itself.
    assert _openbricks_native.motor_process.count == 2
    db.straight(50)
    assert approx(robot.chassis.travel_mm - travel, 50, 1.5)
    assert approx(robot.chassis.heading_deg, heading, 0.5)


def test_estop_releases_an_adopted_wheel_under_a_direct_command_and_refuses_the_next_one():
    robot = ServoRobot()
    robot.drivebase()
    robot.left.run_speed(300)
    time.sleep_ms(300)
    estop.engage("test")
    time.sleep_ms(2)
    assert robot.servos[0].reg16(scs.REG_TORQUE_ENABLE) & 0xFF == 0
    with raises(estop.EStopError, "left wheel.run_speed refused: e-stop engaged"):
        robot.left.run_speed(100)
    robot.left.coast()  # releasing is always allowed


def test_other_motors_on_the_chain_are_adopted_too_and_keep_working():
    robot = ServoRobot(extra_ids=(5,))
    robot.drivebase()
    arm = robot.extras[0]
    assert arm.slot == 2
    arm.run_angle(200, 90)
    assert approx(robot.bus.servo(5).angle_deg(), 90, 2)


def test_a_second_drive_base_over_the_same_wheels_reuses_their_slots():
    robot = ServoRobot()
    robot.drivebase()
    db = robot.drivebase()
    assert (robot.left.slot, robot.right.slot) == (0, 1)
    assert robot.engine().stats(1)[0] > 0
    db.straight(100)
    assert approx(robot.chassis.x_mm, 100, 2)


def test_brake_and_hold_on_an_adopted_wheel_are_allowed_during_an_estop():
    robot = ServoRobot()
    robot.drivebase()
    robot.left.run_speed(300)
    time.sleep_ms(300)
    estop.engage("test")
    robot.left.brake()  # stops are always allowed, as on a motor no drive base adopted
    robot.right.hold()
    time.sleep_ms(500)
    assert abs(robot.servos[0].speed_dps()) < 2
    with raises(estop.EStopError, "left wheel.dc refused: e-stop engaged"):
        robot.left.dc(50)


def _servo_controllers():
    """Native Servo controllers subscribed to motor_process (none while st_move_core runs the moves)."""
    subscribers = _openbricks_native.motor_process.subscribers()
    return [sub for sub in subscribers if isinstance(sub, _openbricks_native.Servo)]


def test_run_angle_on_an_adopted_wheel_runs_on_the_engine_and_done_reads_its_arrival_flag():
    robot = ServoRobot()
    robot.drivebase()
    start = robot.servos[0].angle_deg()
    robot.left.run_angle(360, 540, wait=False)
    slot = robot.left.slot
    assert not robot.left.done()
    assert not robot.engine().done(slot)
    # The move is the engine's own per-slot core (st_move_core): no servo controller in Python's hands.
    assert _servo_controllers() == []
    time.sleep_ms(2500)  # the tick advances the move with nobody polling done()
    assert robot.engine().done(slot)
    assert robot.left.done()
    assert approx(robot.servos[0].angle_deg() - start, 540, 2)


def test_hold_on_an_adopted_wheel_is_a_position_lock_on_the_engine_that_resists_a_push():
    robot = ServoRobot()
    robot.drivebase()
    robot.right.hold()
    held = robot.servos[1].angle_deg()
    assert _servo_controllers() == []
    time.sleep_ms(100)
    robot.servos[1].turn_shaft(20)  # pushed by hand
    time.sleep_ms(800)
    assert approx(robot.servos[1].angle_deg(), held, 1.5)
    assert robot.servos[1].torque_enabled


def test_the_stall_flag_of_an_adopted_wheel_comes_from_the_engine():
    robot = ServoRobot()
    robot.drivebase()
    slot = robot.left.slot
    assert not robot.engine().stalled(slot)
    robot.servos[0].block()
    robot.left.run_speed(300)
    time.sleep_ms(600)
    assert robot.engine().stalled(slot, 80, 20)
    assert robot.left.stalled()
    robot.servos[0].unblock()
    robot.left.coast()


def test_drive_wheel_runs_the_servos_own_speed_loop_and_still_lands_its_moves():
    from openbricks.robotics import DriveBase
    from tests.openbricks.robotics.robots import SERVO_TRACK_MM

    robot = ServoRobot()
    db = DriveBase(
        robot.left, robot.right, wheel_diameter_mm=SERVO_WHEEL_MM, axle_track_mm=SERVO_TRACK_MM, drive="wheel"
    )
    assert [servo.mode for servo in robot.servos] == [1, 1]  # wheel mode: the servo's speed controller
    db.straight(300)
    assert approx(robot.chassis.x_mm, 300, 3)
    db.turn(90)
    assert approx(robot.chassis.heading_deg, 90, 1.5)


def test_drive_must_be_duty_or_wheel_and_wheel_needs_serial_bus_servos():
    from openbricks.robotics import DriveBase
    from tests.openbricks.robotics.robots import SERVO_TRACK_MM

    robot = ServoRobot()
    with raises(ValueError, "DriveBase(drive='speed'): give 'duty' (the default"):
        DriveBase(
            robot.left,
            robot.right,
            wheel_diameter_mm=SERVO_WHEEL_MM,
            axle_track_mm=SERVO_TRACK_MM,
            drive="speed",
        )


def test_drive_wheel_on_encoder_motors_says_they_have_no_speed_controller_of_their_own():
    from openbricks.robotics import DriveBase
    from tests.openbricks.robotics.robots import EncoderRobot

    robot = EncoderRobot()
    with raises(ValueError, "selects the serial-bus servos' own speed controller; JGB37Motor / JGB37Motor"):
        DriveBase(robot.left, robot.right, wheel_diameter_mm=56, axle_track_mm=120, drive="wheel")


def test_a_mixed_pair_is_refused():
    from openbricks.drivers.l298n import L298NMotor
    from openbricks.drivers.st3032 import ST3032Motor
    from openbricks.robotics import DriveBase

    clean_slate()
    bus = ScsBus()
    bus.add(FakeServo(1))
    machine.board.attach_uart(1, bus)
    servo = ST3032Motor(servo_id=1)
    bridge = L298NMotor(9, 10, 11)
    with raises(
        TypeError,
        "the left motor (ST3032Motor) is a serial-bus servo but the right one (L298NMotor) is an open-loop",
    ):
        DriveBase(servo, bridge, wheel_diameter_mm=SERVO_WHEEL_MM, axle_track_mm=SERVO_TRACK_MM)
