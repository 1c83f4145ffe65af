"""The native control path: controllers ticked inside the physics step, with no Python per step."""

import sys

import mujoco
import pytest

import openbricks_native as native
from openbricks_sim import physics as physics_module
from openbricks_sim.physics import Physics


@pytest.fixture
def physics():
    p = Physics("empty", "st3032")
    native.motor_process.reset()
    yield p
    native.motor_process.reset()
    p.close()


def python_calls_during(action):
    """How many Python-level function calls `action` makes, itself excluded."""
    calls = []

    def profile(frame, event, arg):
        if event == "call":
            calls.append(frame.f_code.co_name)

    sys.setprofile(profile)
    try:
        action()
    finally:
        sys.setprofile(None)
    return [name for name in calls if name != "<lambda>"]


def test_a_servo_on_native_wheel_io_tracks_a_speed_with_no_python_per_step(physics):
    controller = physics.attach_control()
    io = physics.wheel_io(0)
    servo = native.Servo(io=io)
    native.motor_process.subscribe(servo)
    servo.run_speed(300.0)
    physics.step(500)
    assert python_calls_during(lambda: controller.step(1000)) == []
    assert io.speed_dps == pytest.approx(300.0, rel=0.03)
    assert servo.speed() == pytest.approx(300.0, rel=0.03)
    assert controller.now_ms == 1500 and native.motor_process.now_ms() == 1499


def test_the_encoder_is_quantised_and_mirrored_by_the_io_sign(physics):
    physics.attach_control()
    forward, mirrored = physics.wheel_io(0), physics.wheel_io(0, sign=-1)
    forward.write_duty(30)
    physics.step(321)
    angle = forward.read_angle()
    assert angle == pytest.approx(physics.wheel_angle_deg(0), abs=360 / 4096)
    assert (angle * 4096 / 360) == pytest.approx(round(angle * 4096 / 360), abs=1e-3), "whole encoder counts"
    assert mirrored.read_angle() == pytest.approx(-angle)
    mirrored.write_duty(30)  # +30 % in the mirrored frame drives the joint backwards
    assert forward.duty_pct == pytest.approx(-30)


def test_a_tick_error_is_raised_once_the_steps_are_done(physics):
    controller = physics.attach_control()
    ticks = []

    def flaky(now_ms):
        ticks.append(now_ms)
        if now_ms == 5:
            raise OSError("sensor unplugged")

    native.motor_process.subscribe(flaky)
    with pytest.raises(OSError, match="sensor unplugged"):
        physics.step(10)
    assert controller.now_ms == 10 and ticks == list(range(10))


def test_mj_forward_between_steps_neither_ticks_nor_advances_time(physics):
    controller = physics.attach_control()
    ticks = []
    native.motor_process.subscribe(ticks.append)
    physics.step(3)
    mujoco.mj_forward(physics.model, physics.data)
    mujoco.mj_forward(physics.model, physics.data)
    assert ticks == [0, 1, 2] and controller.now_ms == 3


def test_a_drivebase_on_native_wheel_io_drives_straight_to_the_millimetre(physics):
    physics.attach_control()
    db = native.DriveBase(88, 138, left_io=physics.wheel_io(0), right_io=physics.wheel_io(1))
    native.motor_process.subscribe(db)
    x0 = physics.pose().x_mm
    db.straight(500, then="hold")
    for _ in range(400):
        physics.step(10)
        if db.done():
            break
    physics.step(300)
    pose = physics.pose()
    assert pose.x_mm - x0 == pytest.approx(500, abs=2.0)
    assert abs(pose.heading_deg) < 0.5


def test_a_silent_wheel_halts_the_drivebase_through_its_watchdog(physics):
    physics.attach_control()
    left = physics.wheel_io(0)
    db = native.DriveBase(88, 138, left_io=left, right_io=physics.wheel_io(1))
    native.motor_process.subscribe(db)
    db.drive(100, 0)
    physics.step(300)
    left.silent = True  # the cable comes out
    physics.step(50)
    with pytest.raises(OSError, match="left"):
        db.done()
    assert left.stats[2] >= 20, "the failed reads in a row are counted"


def test_controllers_refuse_a_bare_or_half_given_motor_io(physics):
    physics.attach_control()
    with pytest.raises(ValueError, match="no IO functions"):
        native.Servo(io=native.MotorIO())
    with pytest.raises(TypeError, match="native motor IO"):
        native.Servo(io=object())
    with pytest.raises(TypeError, match="not a mix"):
        native.DriveBase(88, 138, left_io=physics.wheel_io(0))


def test_a_controller_cannot_be_moved_onto_another_mjdata(physics):
    # Its wheels and every WheelIO point into the MjData it was built on: re-initialising it onto
    # another one would leave them reading and writing the old, possibly freed, arrays.
    controller = physics.attach_control()
    io = physics.wheel_io(0)
    other = mujoco.MjData(physics.model)
    with pytest.raises(RuntimeError, match="already initialised"):
        controller.__init__(physics.model, other, physics_module._mj_step_address())
    io.write_duty(40)
    physics.step(50)
    assert io.read_angle() == pytest.approx(physics.wheel_angle_deg(0), abs=360 / 4096)
    assert io.read_angle() > 0.0, "the wheel on the original MjData is still driven"
