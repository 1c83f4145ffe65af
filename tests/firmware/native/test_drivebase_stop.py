"""stop(then=...) on a moving chassis: how fast it really decelerates and what it leaves the wheels in."""

import pytest

import openbricks_native as native
from tests.firmware.native.drivebase_rig import (
    AXLE_TRACK_MM,
    MM_PER_WHEEL_DEG,
    WHEEL_DIAMETER_MM,
    Chassis,
    Rig,
)

CRUISE_DPS = 500.0


def cruising(acceleration=1500.0, turn_rate_dps=0.0):
    db = native.DriveBase(WHEEL_DIAMETER_MM, AXLE_TRACK_MM)
    db.settings(acceleration=acceleration)
    rig = Rig(db.update, Chassis())
    db.drive(CRUISE_DPS * MM_PER_WHEEL_DEG, turn_rate_dps)
    rig.run_until(db.done, 3000)
    rig.run(300)
    return db, rig


def fitted_deceleration(samples):
    """Least-squares slope of the mean wheel speed against time, deg/s^2, over the given samples."""
    ts = [s.t_ms / 1000.0 for s in samples]
    vs = [0.5 * (s.speeds_dps[0] + s.speeds_dps[1]) for s in samples]
    t_mean = sum(ts) / len(ts)
    v_mean = sum(vs) / len(vs)
    num = sum((t - t_mean) * (v - v_mean) for t, v in zip(ts, vs, strict=True))
    den = sum((t - t_mean) ** 2 for t in ts)
    return -num / den


@pytest.mark.parametrize("acceleration", [1500.0, 800.0])
def test_brake_decelerates_at_the_acceleration_setting_then_leaves_zero_duty(acceleration):
    db, rig = cruising(acceleration)
    start = len(rig.trace)
    db.stop(then="brake")
    elapsed = rig.run_until(db.done, 3000)
    rig.run(200)
    ramp = rig.trace[start : start + elapsed]
    # The middle of the ramp: clear of the transients where it starts and ends.
    middle = ramp[len(ramp) // 5 : 4 * len(ramp) // 5]
    measured = fitted_deceleration(middle)
    assert measured == pytest.approx(acceleration, rel=0.05), f"decelerated at {measured:.0f} deg/s^2"
    assert elapsed / 1000.0 == pytest.approx(CRUISE_DPS / acceleration, abs=0.03), f"ramp took {elapsed} ms"
    assert rig.trace[-1].duties == (0.0, 0.0), "brake ends with both bridges at zero duty (not released)"
    assert max(abs(v) for v in rig.trace[-1].speeds_dps) < 1.0


def test_brake_while_turning_keeps_the_arc_through_the_ramp():
    db, rig = cruising(turn_rate_dps=60.0)
    start = len(rig.trace)
    left0, right0 = rig.trace[-1].speeds_dps
    db.stop(then="brake")
    rig.run_until(db.done, 3000)
    ramp = rig.trace[start:]
    mid = ramp[len(ramp) // 2]
    assert mid.speeds_dps[1] / mid.speeds_dps[0] == pytest.approx(right0 / left0, rel=0.05)


def test_hold_decelerates_then_holds_where_the_robot_came_to_rest():
    db, rig = cruising()
    db.stop(then="hold")
    rig.run_until(db.done, 3000)
    rig.run(50)
    x_rest = rig.chassis.x_mm
    for wheel in rig.chassis.wheels:
        wheel.load_torque_nm = -0.2  # a push backwards
    rig.run(1000)
    assert all(d is not None for d in rig.trace[-1].duties), "hold keeps the wheels under control"
    assert rig.chassis.x_mm == pytest.approx(x_rest, abs=0.5), "hold must resist the push"


def test_coast_releases_both_wheels_at_once():
    db, rig = cruising()
    db.stop()
    assert db.done()
    assert rig.period() == (None, None)
    rig.run(50)
    speed = rig.trace[-1].speeds_dps[0]
    assert 0 < speed < CRUISE_DPS, "a released wheel free-wheels down, slowly"


@pytest.mark.parametrize(
    ("then", "end_state"),
    [
        ("stop", "released"),
        ("coast", "released"),
        ("brake", "zero duty"),
        ("hold", "held"),
        ("continue", "held"),
    ],
)
def test_stop_accepts_every_then_spelling_of_the_manual(then, end_state):
    db, rig = cruising()
    db.stop(then=then)
    rig.run_until(db.done, 3000)
    rig.run(100)
    duties = rig.trace[-1].duties
    if end_state == "released":
        assert duties == (None, None)
        return
    assert max(abs(v) for v in rig.trace[-1].speeds_dps) < 5.0, "decelerated to rest"
    if end_state == "zero duty":
        assert duties == (0.0, 0.0)
    else:
        assert None not in duties, "continue has no cruise to carry on a stop: it holds"
