"""Trapezoidal / triangular profiles of the trajectory core, through the host binding."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import example, given, settings
from hypothesis import strategies as st

from openbricks_native import TrapezoidalProfile


def f32(x: float) -> float:
    """The value a float argument takes inside the core."""
    return float(np.float32(x))


def samples(profile: TrapezoidalProfile, n: int = 400, tail_s: float = 0.2) -> np.ndarray:
    """(t, x, v, a) rows from the start to a little past the end."""
    end = profile.duration_s + tail_s
    return np.array([(t, *profile.sample(t)) for t in np.linspace(0.0, end, n)])


def boundary_jumps(profile: TrapezoidalProfile, eps_s: float = 1e-6) -> list[tuple[float, float]]:
    """Position and speed jumps across each phase boundary, beyond what eps_s of motion explains
    (the sample times are float32 too: each may be off by half an ulp of the boundary time)."""
    jumps = []
    for t in profile.phase_end_s:
        if t <= 2 * eps_s:
            continue
        x0, v0, a0 = profile.sample(t - eps_s)
        x1, v1, a1 = profile.sample(t + eps_s)
        span_s = 2 * eps_s + float(np.spacing(f32(t)))
        jumps.append(
            (
                abs(x1 - x0) - span_s * max(abs(v0), abs(v1)),
                abs(v1 - v0) - span_s * max(abs(a0), abs(a1)),
            )
        )
    return jumps


class TestTrapezoid:
    def test_accel_cruise_decel_phases(self):
        p = TrapezoidalProfile(0.0, 90.0, 300.0, 1500.0)
        assert p.phase_end_s == pytest.approx((0.2, 0.3, 0.5), abs=1e-6)
        assert p.phase_x_deg == pytest.approx((0.0, 30.0, 60.0, 90.0), abs=1e-4)
        assert p.phase_v_dps == pytest.approx((0.0, 300.0, 300.0, 0.0), abs=1e-4)
        assert p.phase_a_dps2 == pytest.approx((1500.0, 0.0, -1500.0))
        assert p.sample(0.1) == pytest.approx((7.5, 150.0, 1500.0), abs=1e-4)
        assert p.sample(0.25) == pytest.approx((45.0, 300.0, 0.0), abs=1e-4)
        assert p.sample(0.4) == pytest.approx((82.5, 150.0, -1500.0), abs=1e-4)

    def test_reverse_move_mirrors_forward(self):
        fwd = TrapezoidalProfile(10.0, 100.0, 300.0, 1500.0, 600.0)
        rev = TrapezoidalProfile(10.0, -80.0, 300.0, 1500.0, 600.0)
        for t in np.linspace(0, fwd.duration_s, 50):
            xf, vf, af = fwd.sample(t)
            xr, vr, ar = rev.sample(t)
            assert (xr - 10.0, vr, ar) == pytest.approx((-(xf - 10.0), -vf, -af), abs=1e-3)

    def test_separate_deceleration(self):
        p = TrapezoidalProfile(0.0, 200.0, 400.0, 2000.0, 500.0)
        t_accel = p.phase_end_s[0]
        t_decel = p.phase_end_s[2] - p.phase_end_s[1]
        assert t_accel == pytest.approx(400 / 2000, rel=1e-5)
        assert t_decel == pytest.approx(400 / 500, rel=1e-5)

    def test_phase_boundaries_are_continuous(self):
        p = TrapezoidalProfile(-30.0, 400.0, 500.0, 1200.0, 3000.0)
        for dx, dv in boundary_jumps(p):
            assert dx < 1e-3 and dv < 1e-2

    def test_before_start_reads_start_and_tail_holds_target(self):
        p = TrapezoidalProfile(5.0, 65.0, 300.0, 1500.0)
        assert p.sample(-1.0) == p.sample(0.0) == (5.0, 0.0, 1500.0)
        assert p.sample(p.duration_s + 100.0) == (65.0, 0.0, 0.0)

    def test_decel_defaults_to_accel(self):
        assert TrapezoidalProfile(0, 100, 300, 900).phase_a_dps2 == pytest.approx((900, 0, -900))


class TestTriangle:
    def test_short_move_never_reaches_cruise(self):
        # 300 deg/s needs 60 deg of ramps at 1500 deg/s^2; 20 deg peaks at sqrt(D * a).
        p = TrapezoidalProfile(0.0, 20.0, 300.0, 1500.0)
        peak = math.sqrt(20.0 * 1500.0)
        t0, t1, t2 = p.phase_end_s
        assert t1 == pytest.approx(t0, abs=1e-6), "no cruise phase"
        assert p.phase_v_dps[1] == pytest.approx(peak, rel=1e-5)
        assert max(v for _, _, v, _ in samples(p)) <= peak + 1e-3
        assert p.sample(t2) == pytest.approx((20.0, 0.0, 0.0))

    def test_asymmetric_triangle_lands_on_target(self):
        p = TrapezoidalProfile(0.0, 10.0, 1000.0, 4000.0, 1000.0)
        _, v_peak, _, _ = p.phase_v_dps
        # d = vp^2/(2a) + vp^2/(2d)
        assert v_peak**2 / 8000 + v_peak**2 / 2000 == pytest.approx(10.0, rel=1e-5)
        assert p.end_deg == 10.0


class TestMovingStart:
    def test_start_speed_toward_target_is_kept(self):
        p = TrapezoidalProfile(0.0, 360.0, 500.0, 1500.0, v0_dps=200.0)
        assert p.sample(0.0) == pytest.approx((0.0, 200.0, 1500.0))
        assert p.phase_end_s[0] == pytest.approx(300 / 1500, rel=1e-5)
        assert p.sample(p.duration_s) == (360.0, 0.0, 0.0)

    def test_start_moving_away_turns_around(self):
        p = TrapezoidalProfile(0.0, 100.0, 300.0, 1000.0, v0_dps=-200.0)
        rows = samples(p, 2000)
        assert rows[:, 1].min() == pytest.approx(-20.0, abs=0.01), "first carries on 200^2/(2*1000) deg away"
        assert p.phase_a_dps2[0] == 1000.0, "one constant acceleration through zero speed"
        for dx, dv in boundary_jumps(p):
            assert dx < 1e-3 and dv < 1e-2
        assert p.sample(p.duration_s + 1) == (100.0, 0.0, 0.0)

    def test_over_speed_start_slows_to_cruise_first(self):
        p = TrapezoidalProfile(0.0, 1000.0, 300.0, 1500.0, 1000.0, v0_dps=800.0)
        assert p.phase_v_dps[:3] == pytest.approx((800.0, 300.0, 300.0))
        assert p.phase_a_dps2[0] == pytest.approx(-1000.0), "slowing down uses the deceleration"
        rows = samples(p, 2000)
        after = rows[rows[:, 0] >= p.phase_end_s[0]]
        assert np.all(np.abs(after[:, 2]) <= 300.0 + 1e-3)
        assert p.end_deg == 1000.0

    def test_too_short_to_stop_raises_deceleration_and_lands_at_rest(self):
        # At 600 deg/s a 1500 deg/s^2 stop needs 120 deg; the target is 20 deg away.
        p = TrapezoidalProfile(0.0, 20.0, 600.0, 1500.0, v0_dps=600.0)
        raised = 600.0**2 / (2 * 20.0)
        assert p.phase_a_dps2[2] == pytest.approx(-raised, rel=1e-5)
        assert p.duration_s == pytest.approx(2 * 20.0 / 600.0, rel=1e-5)
        rows = samples(p, 1000)
        assert rows[:, 1].max() <= 20.0, "never past the target"
        assert np.all(np.diff(rows[:, 1]) >= -1e-6), "never moves back"
        assert p.sample(p.duration_s) == (20.0, 0.0, 0.0)

    def test_moving_while_on_target_comes_back(self):
        p = TrapezoidalProfile(50.0, 50.0, 300.0, 1000.0, v0_dps=100.0)
        rows = samples(p, 2000)
        assert rows[:, 1].max() == pytest.approx(55.0, abs=0.01), (
            "stops 100^2/(2*1000) deg past, then returns"
        )
        assert p.sample(p.duration_s) == (50.0, 0.0, 0.0)


class TestEndAtCruise:
    def test_ends_on_target_at_cruise_and_keeps_going(self):
        p = TrapezoidalProfile(0.0, 180.0, 400.0, 1600.0, end_at_cruise=True)
        assert p.sample(p.duration_s) == pytest.approx((180.0, 400.0, 0.0))
        assert p.sample(p.duration_s + 0.5) == pytest.approx((380.0, 400.0, 0.0))
        assert p.phase_a_dps2[2] == 0.0, "no deceleration phase"

    def test_too_short_for_cruise_ends_at_speed_reached(self):
        p = TrapezoidalProfile(0.0, 20.0, 1000.0, 2000.0, end_at_cruise=True)
        reached = math.sqrt(2 * 2000.0 * 20.0)
        assert p.sample(p.duration_s) == pytest.approx((20.0, reached, 0.0), rel=1e-5)

    def test_continues_from_a_moving_start(self):
        p = TrapezoidalProfile(0.0, -300.0, 500.0, 1500.0, v0_dps=-500.0, end_at_cruise=True)
        assert p.duration_s == pytest.approx(300 / 500, rel=1e-5)
        assert p.sample(p.duration_s) == pytest.approx((-300.0, -500.0, 0.0))


class TestSpeedRampAndHold:
    def test_speed_ramp_then_constant_speed(self):
        p = TrapezoidalProfile.speed_ramp(10.0, -100.0, 500.0, 2000.0)
        assert p.duration_s == pytest.approx(0.3, rel=1e-5)
        x_end = 10.0 + (500.0**2 - 100.0**2) / (2 * 2000.0)
        assert p.sample(0.3) == pytest.approx((x_end, 500.0, 0.0), rel=1e-5)
        assert p.sample(1.3) == pytest.approx((x_end + 500.0, 500.0, 0.0), rel=1e-5)

    def test_hold(self):
        p = TrapezoidalProfile.hold(42.0)
        assert p.sample(0.0) == p.sample(7.0) == (42.0, 0.0, 0.0)
        assert p.duration_s == 0.0


class TestScaled:
    def test_scaled_profile_keeps_the_ratio_at_every_sample(self):
        forward = TrapezoidalProfile(0.0, 500.0, 400.0, 1500.0, 800.0, v0_dps=120.0)
        k = -0.37
        heading = forward.scaled(k, 30.0)
        for t in np.linspace(-0.1, forward.duration_s + 0.3, 300):
            x, v, a = forward.sample(t)
            hx, hv, ha = heading.sample(t)
            assert hx - 30.0 == pytest.approx(k * x, abs=1e-3)
            assert hv == pytest.approx(k * v, abs=1e-3)
            assert ha == pytest.approx(k * a, abs=1e-2)
        assert heading.duration_s == forward.duration_s


class TestValidation:
    @pytest.mark.parametrize(
        ("kwargs", "message"),
        [
            ({"speed_dps": 0.0}, "speed_dps must be > 0"),
            ({"accel_dps2": -5.0}, "accel_dps2 must be > 0"),
            ({"decel_dps2": 0.0}, "decel_dps2 must be > 0"),
            ({"target_deg": float("nan")}, "target_deg must be a finite number"),
            ({"v0_dps": float("inf")}, "v0_dps must be a finite number"),
        ],
    )
    def test_bad_numbers_name_the_argument(self, kwargs, message):
        args = {"x0_deg": 0.0, "target_deg": 90.0, "speed_dps": 100.0, "accel_dps2": 500.0} | kwargs
        with pytest.raises(ValueError, match=message):
            TrapezoidalProfile(**args)

    def test_non_number_is_a_type_error(self):
        with pytest.raises(TypeError, match="speed_dps must be a number, not str"):
            TrapezoidalProfile(0.0, 90.0, "fast", 500.0)


# ---- Invariants over arbitrary moves. ----

positions = st.floats(-5000.0, 5000.0)
moves = st.tuples(
    positions,  # x0
    st.floats(-3000.0, 3000.0),  # signed distance
    st.floats(1.0, 2000.0),  # speed
    st.floats(10.0, 20000.0),  # accel
    st.floats(10.0, 20000.0),  # decel
    st.one_of(st.just(0.0), st.floats(-3000.0, 3000.0)),  # start speed
)


def rest_profile(move):
    x0, distance, speed, accel, decel, v0 = move
    return TrapezoidalProfile(x0, x0 + distance, speed, accel, decel, v0_dps=v0), f32(x0 + distance)


@settings(max_examples=300, deadline=None)
@given(moves)
def test_moves_end_exactly_on_target_at_rest(move):
    p, target = rest_profile(move)
    assert p.sample(p.duration_s) == (target, 0.0, 0.0)
    assert p.sample(p.duration_s + 10.0) == (target, 0.0, 0.0)
    assert p.end_deg == target


@settings(max_examples=300, deadline=None)
@given(moves)
def test_moves_never_overshoot_a_target_they_end_at_rest_on(move):
    p, target = rest_profile(move)
    x0 = f32(move[0])
    rows = samples(p, 600, tail_s=0.0)
    last_phase = rows[rows[:, 0] >= p.phase_end_s[1]]
    d = float(np.float32(target) - np.float32(x0))
    if abs(d) < 1e-4:
        # Already on target: a moving start overshoots by necessity and comes back from the far side.
        direction = -math.copysign(1.0, move[5]) if move[5] else 1.0
    else:
        direction = math.copysign(1.0, d)
    overshoot = direction * (rows[:, 1] - target)
    # A start already (fractionally) past the target is the only excursion beyond it.
    allowed = max(0.0, direction * (f32(x0) - target))
    assert overshoot.max() <= allowed, f"passes the target by {overshoot.max()} deg"
    # The approach to rest is monotonic: never backs up in the last phase.
    assert np.all(direction * np.diff(last_phase[:, 1]) >= -1e-4)


@settings(max_examples=300, deadline=None)
@given(moves)
def test_speed_never_exceeds_the_limit_unless_the_start_did(move):
    p, _ = rest_profile(move)
    speed, v0 = move[2], move[5]
    bound = max(f32(speed), abs(f32(v0)))
    rows = samples(p, 600)
    assert np.abs(rows[:, 2]).max() <= bound * (1 + 1e-6)
    if abs(v0) <= speed:
        assert np.abs(rows[:, 2]).max() <= f32(speed) * (1 + 1e-6)


@settings(max_examples=200, deadline=None)
@given(moves)
@example(move=(0.0, 0.0, 137.0, 14239.150390625, 3373.66818875526, 312.8679459219802))  # time rounding
@example(move=(0.0, 179.0, 717.0, 13.0, 1433.0, 716.0))  # peak a hair above the start, tiny accel
@example(move=(0.0, 1e-05, 1.0, 10.0, 10.0, 1.0))  # moving, a hair short of the target: turns round
def test_samples_are_continuous_across_phases(move):
    p, _ = rest_profile(move)
    # Float32 rounding is the only allowed jump: a couple of ulps of the largest term a sample adds up
    # (the position reached, or v*t of a phase that turns round and cancels most of it).
    rows = samples(p, 400)
    scale = max(1.0, np.abs(rows[:, 1]).max(), np.abs(rows[:, 2]).max() * p.duration_s)
    for dx, dv in boundary_jumps(p, eps_s=1e-7):
        assert dx <= 4e-7 * scale
        assert dv <= 1e-5 * max(move[2], abs(move[5]), 1.0) + 1e-3


@settings(max_examples=200, deadline=None)
@given(moves)
def test_end_at_cruise_reaches_target_moving_toward_it(move):
    x0, distance, speed, accel, decel, v0 = move
    p = TrapezoidalProfile(x0, x0 + distance, speed, accel, decel, v0_dps=v0, end_at_cruise=True)
    x, v, a = p.sample(p.duration_s)
    assert x == f32(x0 + distance)
    if abs(distance) >= 1e-3:
        assert v * distance > 0 or v == 0.0, "arrives moving toward where the target was"
        assert abs(v) <= max(f32(speed), abs(f32(v0))) * (1 + 1e-6)
