"""ST-3032: the ST-3215 driver with the ST-3032 datasheet's speed and torque."""

import time

import machine

from fakes.expect import approx
from fakes.scs_servo import FakeServo, ScsBus
from openbricks import pins
from openbricks.drivers import st3215
from openbricks.drivers.st3032 import ST3032, ST3032Motor
from openbricks.drivers.st3215 import ST3215Motor, SyncServoGroup
from tests.openbricks.drivers.test_st3215 import _bus

NEEDS_NATIVE = True  # the servos are the simulator's, on the native SCS codec


def test_the_speed_clamp_defaults_to_the_datasheet_no_load_speed_not_the_st3215s_600():
    bus = _bus(1)
    m = ST3032Motor(1)
    m.run_speed(2000)
    time.sleep_ms(1500)
    assert approx(bus.servo(1).speed_dps(), 888, 1)
    assert approx(m.speed(), 888, 1)


def test_load_is_scaled_by_the_st3032_stall_torque():
    bus = _bus(1)
    m = ST3032Motor(1)
    bus.servo(1).block()
    m.run_speed(100)
    time.sleep_ms(100)
    assert approx(m.load(), 980, 1)
    assert m.stalled()


def test_st3032_and_st3215_share_one_daisy_chain():
    bus = _bus(1, 2, 3)
    left = ST3032Motor(1)
    right = ST3215Motor(2, invert=True)
    gripper = ST3032(3)
    assert left.bus is right.bus is gripper.bus
    SyncServoGroup([left, right]).set_goal_speeds([300, 300])
    gripper.move_to(45)
    time.sleep_ms(500)
    assert approx(bus.servo(1).speed_dps(), 300, 1)
    assert approx(bus.servo(2).speed_dps(), -300, 1)
    assert approx(gripper.angle(), 45, 0.2)


def test_drivebase_style_construction_from_the_manual():
    _bus(1, 2)
    left = ST3032Motor(servo_id=1, uart_id=1, tx=14, rx=41)
    right = ST3032Motor(servo_id=2, uart_id=1, tx=14, rx=41, invert=True)
    assert (left.servo_id, left.invert, right.servo_id, right.invert) == (1, False, 2, True)
    assert left.max_dps == right.max_dps == 888.0


def test_serial_bus_motors_have_migrate_bus_to_native():
    st3215.forget_buses()
    pins.reset_claims()
    bus = ScsBus()
    bus.add(FakeServo(1))
    machine.board.attach_uart(1, bus)
    motor = ST3032Motor(servo_id=1, uart_id=1, tx=14, rx=41)
    try:
        ST3032Motor.migrate_bus_to_native(motor.bus, skip=())
        raise AssertionError("a bus no engine owns has nothing to migrate to")
    except RuntimeError as exc:
        assert "DriveBase adopts its wheels first" in str(exc)
