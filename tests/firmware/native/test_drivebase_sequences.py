"""Any sequence of straights and turns ends where dead reckoning of the commands says it should."""

import math

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import openbricks_native as native
from tests.firmware.native.drivebase_rig import AXLE_TRACK_MM, WHEEL_DIAMETER_MM, Chassis, Rig

moves = st.lists(
    st.one_of(
        st.tuples(st.just("straight"), st.floats(-300, 300).filter(lambda d: abs(d) > 0.5)),
        st.tuples(st.just("turn"), st.floats(-200, 200).filter(lambda a: abs(a) > 0.5)),
    ),
    min_size=1,
    max_size=4,
)


@settings(max_examples=15, deadline=None)
@given(moves=moves, then=st.sampled_from(["coast", "brake", "hold"]))
def test_straight_and_turn_sequences_land_on_the_dead_reckoned_pose(moves, then):
    db = native.DriveBase(WHEEL_DIAMETER_MM, AXLE_TRACK_MM)
    rig = Rig(db.update, Chassis())
    x = y = heading = 0.0
    for kind, amount in moves:
        if kind == "straight":
            db.straight(amount, then=then)
            x += amount * math.cos(math.radians(-heading))
            y += amount * math.sin(math.radians(-heading))
        else:
            db.turn(amount, then=then)
            heading += amount
        rig.run_until(db.done, 10_000)
    rig.run(300)
    c = rig.chassis
    # Each move is accurate to ~0.1 mm / 0.15 deg; a heading error also swings the later straights.
    assert c.heading_deg == pytest.approx(heading, abs=0.2 * len(moves))
    assert math.hypot(c.x_mm - x, c.y_mm - y) < 1.0 * len(moves), f"ended at ({c.x_mm:.1f}, {c.y_mm:.1f})"
