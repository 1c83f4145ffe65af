"""DriveBase on two open-loop L298N channels: drive() and stop() map straight onto the bridges; anything
that needs feedback refuses with an error that says what to use instead.

No native core is involved, so these run under MicroPython too."""

from machine import board

from fakes.expect import approx, raises
from openbricks import pins
from openbricks.drivers import st3215
from openbricks.drivers.l298n import L298NMotor
from openbricks.robotics import DriveBase

WHEEL_MM = 65.0
TRACK_MM = 150.0


def clean_slate():
    pins.reset_claims()
    st3215.forget_buses()


def _drivebase():
    clean_slate()
    left = L298NMotor(1, 2, 17)
    right = L298NMotor(9, 10, 11, invert=True)
    return DriveBase(left, right, wheel_diameter_mm=WHEEL_MM, axle_track_mm=TRACK_MM)


def _bridge(in1, in2, pwm):
    """Duty the winding sees: +/- percent, 0.0 when shorted (brake), None when off (coast)."""
    a, b = board.pins[in1].value(), board.pins[in2].value()
    enable = board.pwms[pwm].duty_u16() * 100.0 / 65535
    if enable == 0 or (a == 0 and b == 0):
        return None
    if a == b:
        return 0.0
    return enable if a else -enable


def _bridges():
    return _bridge(1, 2, 17), _bridge(9, 10, 11)


def test_drive_maps_speed_and_turn_rate_onto_both_bridges():
    db = _drivebase()
    db.drive(200, 0)
    left, right = _bridges()
    # 200 mm/s on a 65 mm wheel is 352.6 wheel-deg/s: 35.3 % of the default 1000 deg/s at full duty.
    assert approx(left, 35.3, 0.2)
    assert approx(right, -35.3, 0.2)  # the mirror-mounted right motor turns the other way for "forward"
    db.drive(0, 90)  # spin clockwise: left forward, right backward
    left, right = _bridges()
    assert left > 0 and right > 0 and approx(left, right, 0.01)


def test_move_wheels_scales_by_the_motor_no_load_speed():
    db = _drivebase()
    db.left.no_load_dps = 400.0
    db.right.no_load_dps = 400.0
    db.move_wheels(200, -100)
    left, right = _bridges()
    assert approx(left, 50, 0.1)
    assert approx(right, 25, 0.1)
    db.move_wheels(2000, 0)
    assert approx(_bridges()[0], 100, 0.01)  # capped at full duty


def test_stop_coasts_or_brakes_both_bridges_and_hold_is_refused():
    db = _drivebase()
    db.drive(150, 0)
    db.stop()
    assert _bridges() == (None, None)
    db.drive(150, 0)
    db.stop(then="brake")
    assert _bridges() == (0.0, 0.0)
    with raises(NotImplementedError, "stop(then='hold') needs position feedback"):
        db.stop(then="hold")


def test_stop_with_wait_stops_the_wheels_then_raises_value_error():
    db = _drivebase()
    db.drive(150, 0)
    with raises(ValueError, "open-loop motors have no speed feedback"):
        db.stop(wait=True)
    assert _bridges() == (None, None)


def test_moves_by_distance_raise_runtime_error_and_leave_the_motors_alone():
    db = _drivebase()
    db.drive(100, 0)
    before = _bridges()
    with raises(RuntimeError, "DriveBase.straight needs wheel feedback"):
        db.straight(100)
    with raises(RuntimeError, "DriveBase.turn needs wheel feedback"):
        db.turn(90)
    with raises(RuntimeError, "use drive() and stop()"):
        db.curve(100, 90)
    assert _bridges() == before


def test_done_is_always_true_and_odometry_is_refused():
    db = _drivebase()
    db.drive(100, 0)
    assert db.done()
    with raises(RuntimeError, "needs wheel feedback"):
        db.distance()
    with raises(RuntimeError, "needs wheel feedback"):
        db.use_gyro(True)


def test_construction_checks_sizes_and_the_drive_mode():
    clean_slate()
    left = L298NMotor(1, 2, 17)
    right = L298NMotor(9, 10, 11)
    with raises(ValueError, "DriveBase(wheel_diameter_mm=0)"):
        DriveBase(left, right, wheel_diameter_mm=0, axle_track_mm=TRACK_MM)
    with raises(ValueError, "DriveBase(drive='speed')"):
        DriveBase(left, right, WHEEL_MM, TRACK_MM, drive="speed")
    with raises(ValueError, "same motor object"):
        DriveBase(left, left, WHEEL_MM, TRACK_MM)
    with raises(TypeError, "is not a motor"):
        DriveBase(left, "right", WHEEL_MM, TRACK_MM)
