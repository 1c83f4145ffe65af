"""The alpha-beta observer against a 4096-count encoder read at 1 kHz."""

from __future__ import annotations

import math

import numpy as np
import pytest

from openbricks_native import Observer

COUNT_DEG = 360.0 / 4096
DT_S = 0.001


def encoder(angle_deg: np.ndarray) -> np.ndarray:
    return np.floor(angle_deg / COUNT_DEG) * COUNT_DEG


def run(observer: Observer, readings: np.ndarray) -> np.ndarray:
    """(x, v) estimates after each reading."""
    return np.array([observer.update(float(r), DT_S) for r in readings])


def test_tracks_an_accelerating_shaft():
    t = np.arange(2000) * DT_S
    accel = 1500.0
    true_x = 3.3 + 0.5 * accel * t**2
    true_v = accel * t
    est = run(Observer(x_deg=float(encoder(true_x[:1])[0])), encoder(true_x))
    settled = slice(300, None)
    speed_error = est[settled, 1] - true_v[settled]
    position_error = est[settled, 0] - true_x[settled]
    # An alpha-beta filter lags a ramp by a * dt * (alpha / beta - 1/2): 10.5 deg/s here, which the servo's
    # acceleration feed-forward covers. Quantisation adds a few deg/s around that.
    assert abs(np.mean(speed_error) + 10.5) < 1.0, f"mean speed error {np.mean(speed_error):.1f} deg/s"
    assert np.abs(speed_error).max() < 20.0, f"speed off by up to {np.abs(speed_error).max():.1f} deg/s"
    assert np.abs(position_error).max() < 0.2, f"position off by up to {np.abs(position_error).max():.3f} deg"


def test_speed_is_far_quieter_than_finite_differences():
    t = np.arange(3000) * DT_S
    true_v = 97.3  # not a whole number of counts per tick, so the reading steps irregularly
    readings = encoder(1.1 + true_v * t)
    est = run(Observer(x_deg=float(readings[0])), readings)
    observer_var = np.var(est[1000:, 1] - true_v)
    differences_var = np.var(np.diff(readings)[1000:] / DT_S - true_v)
    ratio = differences_var / observer_var
    # The manual promises about 60x; the default gains give several times that.
    assert ratio > 60.0, f"variance only {ratio:.0f}x lower than finite differences"
    assert abs(np.mean(est[1000:, 1]) - true_v) < 0.5


def test_silent_reading_coasts_the_estimate_and_recovers():
    ob = Observer()
    for i in range(500):
        ob.update(200.0 * i * DT_S, DT_S)
    x, v = ob.predict(0.010)
    assert v == pytest.approx(200.0, abs=1.0)
    assert x == pytest.approx(200.0 * 0.509, abs=0.1), "predicts along at the estimated speed"
    for i in range(510, 800):
        x, v = ob.update(200.0 * i * DT_S, DT_S)
    assert x == pytest.approx(200.0 * 0.799, abs=0.01)


def test_zero_dt_update_changes_nothing():
    ob = Observer(x_deg=10.0)
    ob.update(10.5, DT_S)
    before = (ob.x_deg, ob.v_dps)
    assert ob.update(99.0, 0.0) == before


def test_a_denormal_dt_does_not_poison_the_estimate():
    # 1 / dt overflows float for dt in the denormal range: such a step is no time at all.
    ob = Observer(x_deg=10.0)
    ob.update(10.5, DT_S)
    before = (ob.x_deg, ob.v_dps)
    assert ob.update(11.0, 1e-40) == before
    x, v = ob.update(11.0, DT_S)
    assert math.isfinite(x) and math.isfinite(v)


def test_reset_snaps_to_rest():
    ob = Observer()
    for i in range(100):
        ob.update(i * 0.5, DT_S)
    ob.reset(42.0)
    assert (ob.x_deg, ob.v_dps) == (42.0, 0.0)


def test_default_and_custom_gains():
    assert (Observer().alpha, Observer().beta) == pytest.approx((0.3, 0.04))
    ob = Observer(alpha=0.5, beta=0.1)
    assert (ob.alpha, ob.beta) == pytest.approx((0.5, 0.1))


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        ({"alpha": 0.0}, r"alpha must be within \(0, 1\]"),
        ({"beta": 1.5}, r"beta must be within \(0, 1\]"),
        ({"x_deg": math.nan}, "x_deg must be a finite number"),
    ],
)
def test_bad_arguments(kwargs, message):
    with pytest.raises(ValueError, match=message):
        Observer(**kwargs)


def test_negative_dt_is_refused():
    with pytest.raises(ValueError, match="dt_s must be >= 0"):
        Observer().update(1.0, -0.001)
