"""Feedback the drivebase steers by: silent wheels, a gyro heading source, and re-zeroing the frame."""

import pytest

import openbricks_native as native
from tests.firmware.native.drivebase_rig import AXLE_TRACK_MM, WHEEL_DIAMETER_MM, Chassis, Rig


def new_rig(chassis=None, gyro=False, **kwargs):
    db = native.DriveBase(WHEEL_DIAMETER_MM, AXLE_TRACK_MM, **kwargs)
    rig = Rig(db.update, chassis or Chassis(), gyro=gyro)
    if gyro:
        db.use_gyro(True)
    rig.run(5)
    return db, rig


@pytest.mark.parametrize(("side", "index"), [("left", 0), ("right", 1)])
def test_a_silent_wheel_halts_the_drivebase_within_50_ms_without_winding_up(side, index):
    db, rig = new_rig()
    db.straight(1000)
    rig.run(1500)  # at cruise
    cruise_duty = max(abs(d) for d in rig.trace[-1].duties)
    silent_from = rig.now_ms
    rig.silent[index] = silent_from
    halted_at = None
    while rig.now_ms - silent_from < 200:
        duties = rig.period()
        if duties == (None, None) and halted_at is None:
            halted_at = rig.now_ms
        if halted_at is None:
            assert max(abs(d) for d in duties) < cruise_duty + 10, f"duty wound up to {duties}"
    assert halted_at is not None, "the drivebase kept driving with a silent wheel"
    assert halted_at - silent_from <= 50, f"halted {halted_at - silent_from} ms after the wheel went silent"
    assert all(s.duties == (None, None) for s in rig.trace if s.t_ms > halted_at), "must stay released"
    assert db.fault() == (side,)
    with pytest.raises(OSError, match=f"the {side} wheel"):
        db.done()


@pytest.mark.parametrize("stall_ms", [100, 200])
def test_a_stalled_caller_resumes_at_cruise_without_a_jolt(stall_ms):
    # A long GC pause on the hub: no control period for stall_ms while the wheels keep their last
    # duty. The first readings afterwards must not read as a speed spike that kicks the duties.
    db, rig = new_rig()
    db.straight(600, then="hold")
    rig.run(700)  # at cruise
    cruise = rig.trace[-1].duties
    for _ in range(stall_ms):
        rig.chassis.step(cruise, 0.001)
        rig.now_ms += 1
    resumed_at = len(rig.trace)
    rig.run(60)
    worst = max(abs(d - c) for s in rig.trace[resumed_at:] for d, c in zip(s.duties, cruise, strict=True))
    assert worst < 5.0, f"duty jumped by {worst:.0f} % after a {stall_ms} ms stall at cruise"
    rig.run_until(db.done, 5000)
    rig.run(300)
    assert rig.chassis.x_mm == pytest.approx(600.0, abs=1.0)


def test_a_drive_repeated_after_a_stalled_caller_keeps_the_robot_running_smoothly():
    # A line follower re-issuing drive() every few ms, and a 40 ms GC pause just before one call:
    # the robot kept going meanwhile, and the new command must carry on from its speed.
    db, rig = new_rig()
    db.drive(200, 0)
    rig.run(600)
    cruise = rig.trace[-1].duties
    for _ in range(40):
        rig.chassis.step(cruise, 0.001)
        rig.now_ms += 1
    db.drive(200, 0)
    resumed_at = len(rig.trace)
    rig.run(100)
    worst = max(abs(d - c) for s in rig.trace[resumed_at:] for d, c in zip(s.duties, cruise, strict=True))
    assert worst < 5.0, f"duty jumped by {worst:.0f} % when drive() came after the pause"


def test_a_new_move_after_the_wheel_returns_clears_the_fault_and_drives_normally():
    db, rig = new_rig()
    db.straight(500)
    rig.run(800)
    rig.silent[1] = rig.now_ms
    rig.run(100)
    assert db.fault() == ("right",)
    del rig.silent[1]
    rig.run(500)  # the robot coasts to rest
    x0 = rig.chassis.x_mm
    db.straight(100)
    assert db.fault() is None
    rig.run_until(db.done, 5000)
    rig.run(300)
    assert rig.chassis.x_mm - x0 == pytest.approx(100, abs=1.0)


def test_a_wheel_already_silent_when_a_move_is_armed_halts_it_at_once():
    db, rig = new_rig()
    rig.silent[0] = 0
    rig.run(100)
    db.straight(100)
    rig.run(2)
    assert rig.trace[-1].duties == (None, None)
    assert db.fault() == ("left",)
    assert abs(rig.chassis.x_mm) < 0.1


def test_gyro_steering_is_immune_to_wheel_slip():
    """The left tyre slips 5 %: the encoders see a straight line, the robot curves; the gyro sees it."""
    slipping = (0.05, 0.0)
    db, rig = new_rig(Chassis(slip=slipping))
    db.straight(1000)
    rig.run_until(db.done, 20_000)
    encoder_heading = rig.chassis.heading_deg

    db, rig = new_rig(Chassis(slip=slipping), gyro=True)
    db.straight(1000)
    rig.run_until(db.done, 20_000)
    rig.run(300)
    gyro_heading = rig.chassis.heading_deg
    assert abs(encoder_heading) > 10, f"slip should fool the encoders ({encoder_heading:.2f} deg)"
    assert abs(gyro_heading) < 0.3, f"with the gyro the robot ended {gyro_heading:.3f} deg off"


def test_gyro_turn_ends_on_the_measured_heading_despite_slip():
    db, rig = new_rig(Chassis(slip=(0.1, 0.1)), gyro=True)
    db.turn(90)
    rig.run_until(db.done, 5000)
    rig.run(300)
    assert rig.chassis.heading_deg == pytest.approx(90, abs=0.2)


def test_switching_to_the_gyro_mid_hold_does_not_jerk_the_robot():
    db, rig = new_rig()
    db.turn(45, then="hold")
    rig.run_until(db.done, 5000)
    rig.run(100)
    before = rig.chassis.heading_deg
    rig.gyro = True
    # The gyro's frame is arbitrary: a heading source that reads 1000 deg off must not matter.
    rig.controller = lambda now, left, right, heading: db.update(now, left, right, heading + 1000.0)
    db.use_gyro(True)
    rig.run(500)
    assert rig.chassis.heading_deg == pytest.approx(before, abs=0.1)
    assert db.angle() == pytest.approx(45, abs=0.2)


@pytest.mark.parametrize("gyro", [False, True])
def test_reset_makes_the_current_pose_zero_and_the_next_move_follows_the_new_frame(gyro):
    db, rig = new_rig(gyro=gyro)
    db.straight(100)
    rig.run_until(db.done, 5000)
    db.turn(-90, then="hold")
    rig.run_until(db.done, 5000)
    rig.run(100)
    heading_before = rig.chassis.heading_deg
    db.reset()
    assert db.distance() == 0.0 and db.angle() == 0.0
    rig.run(100)
    assert rig.chassis.heading_deg == pytest.approx(heading_before, abs=0.05), (
        "reset must not move a held robot"
    )
    db.straight(130)
    rig.run_until(db.done, 5000)
    rig.run(300)
    c = rig.chassis
    # Heading -90 (left) from (100, 0): the new straight runs along +y.
    assert c.heading_deg == pytest.approx(heading_before, abs=0.2), "the straight must keep the new zero"
    assert (c.x_mm, c.y_mm) == pytest.approx((100, 130), abs=1.5)
    assert db.distance() == pytest.approx(130, abs=0.5)
    assert db.angle() == pytest.approx(0, abs=0.2)


def test_a_drivebase_built_on_wheels_that_turned_before_starts_at_zero():
    # The wheels' encoders read 720 deg (their motors ran before the drive base was built) and the
    # first move is armed before the first period, as the runtime does right after subscribing.
    chassis = Chassis()
    for wheel, angle in zip(chassis.wheels, (720.0, 540.0), strict=True):
        wheel.angle_deg = angle
    db = native.DriveBase(WHEEL_DIAMETER_MM, AXLE_TRACK_MM)
    rig = Rig(db.update, chassis)
    db.straight(300)
    rig.run(1)
    assert db.state()[0] == pytest.approx(0.0, abs=0.1) and db.state()[2] == pytest.approx(0.0, abs=0.1)
    rig.run_until(db.done, 5000)
    rig.run(300)
    assert rig.chassis.x_mm == pytest.approx(300.0, abs=1.0)
    assert abs(rig.chassis.heading_deg) < 0.5
    assert db.distance() == pytest.approx(300.0, abs=1.0)


def test_a_move_armed_after_the_drivebase_was_not_ticked_starts_where_the_robot_is():
    # Two drive bases on the same wheels: the runtime unsubscribes one while the other drives, and
    # subscribes it again right before its next move. That move must not drive back to where the
    # robot stood when the first one last ran.
    db, rig = new_rig()
    db.straight(200)
    rig.run_until(db.done, 5000)
    rig.run(200)
    other = native.DriveBase(WHEEL_DIAMETER_MM, AXLE_TRACK_MM)
    rig.controller = other.update
    other.straight(300)
    rig.run_until(other.done, 5000)
    rig.run(300)
    here = rig.chassis.x_mm
    rig.controller = db.update
    db.straight(100)
    resumed_at = len(rig.trace)
    rig.run_until(db.done, 5000)
    rig.run(300)
    assert min(s.x_mm for s in rig.trace[resumed_at:]) > here - 1.0, "drove back"
    assert rig.chassis.x_mm == pytest.approx(here + 100.0, abs=1.0)
    assert db.distance() == pytest.approx(600.0, abs=1.0), "odometry counts what the wheels did meanwhile"


def test_reset_is_refused_while_a_move_is_in_progress():
    db, rig = new_rig()
    db.straight(300)
    rig.run(200)
    with pytest.raises(RuntimeError, match="move is in progress"):
        db.reset()
    db.stop()
    db.reset()
