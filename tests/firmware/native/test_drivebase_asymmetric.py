"""One weak wheel (0.9x output at a given duty): the coupled controller keeps the robot straight.

Exit criterion of the drivebase (manual 8.2): the heading error stays under 5 % of the forward distance.
The rig measures it as what a heading error does to a robot, the sideways drift it causes, taken as the
worst |lateral offset| / distance travelled over the whole run (after the first 100 mm, where the ratio
of two small numbers means nothing). A pure proportional controller of the kind the coupled one
replaced, run on the same chassis and the same trajectory, must fail it: that is what makes the test
discriminating rather than a restatement of the controller.
"""

import math

import pytest

import openbricks_native as native
from tests.firmware.native.drivebase_rig import (
    AXLE_TRACK_MM,
    MM_PER_WHEEL_DEG,
    WHEEL_DIAMETER_MM,
    Chassis,
    Rig,
)

DISTANCE_MM = 1000.0
ACCELERATION_DPS2 = 1500.0
WEAK = (1.0, 0.9)  # right wheel at 0.9x
# Cruise close to the strong wheel's top speed: the weak one cannot follow by duty alone, which is where
# the two ways of sharing the duty range part company.
FAST_DPS = 800.0


def drift_ratio(trace) -> float:
    return max(abs(s.y_mm) / s.x_mm for s in trace if s.x_mm > 100.0)


def trapezoid(distance_deg: float, speed_dps: float, accel_dps2: float):
    """Reference position over time for the pure-P controller: the same shape the core plans."""
    t_ramp = speed_dps / accel_dps2
    d_ramp = 0.5 * accel_dps2 * t_ramp**2
    if 2 * d_ramp > distance_deg:
        t_ramp = math.sqrt(distance_deg / accel_dps2)
        speed_dps = accel_dps2 * t_ramp
        d_ramp = 0.5 * distance_deg
    t_cruise = (distance_deg - 2 * d_ramp) / speed_dps
    total = 2 * t_ramp + t_cruise

    def position(t: float) -> float:
        if t <= 0:
            return 0.0
        if t < t_ramp:
            return 0.5 * accel_dps2 * t * t
        if t < t_ramp + t_cruise:
            return d_ramp + speed_dps * (t - t_ramp)
        if t < total:
            left = total - t
            return distance_deg - 0.5 * accel_dps2 * left * left
        return distance_deg

    return position, total


class PureP:
    """Each wheel chases the shared reference with duty = kp * error: no coupling, no integral, no model."""

    def __init__(self, kp: float, speed_dps: float):
        self.kp = kp
        self.reference, self.duration_s = trapezoid(
            DISTANCE_MM / MM_PER_WHEEL_DEG, speed_dps, ACCELERATION_DPS2
        )

    def __call__(self, now_ms, left_deg, right_deg):
        ref = self.reference(now_ms / 1000.0)
        return tuple(max(-100.0, min(100.0, self.kp * (ref - x))) for x in (left_deg, right_deg))


def run_coupled(speed_dps: float) -> Rig:
    db = native.DriveBase(WHEEL_DIAMETER_MM, AXLE_TRACK_MM)
    db.settings(straight_speed=speed_dps, acceleration=ACCELERATION_DPS2)
    rig = Rig(db.update, Chassis(effectiveness=WEAK))
    db.straight(DISTANCE_MM)
    rig.run_until(db.done, 20_000)
    rig.run(300)
    return rig


def run_pure_p(kp: float, speed_dps: float) -> Rig:
    controller = PureP(kp, speed_dps)
    rig = Rig(controller, Chassis(effectiveness=WEAK))
    rig.run(int(controller.duration_s * 1000) + 800)
    return rig


@pytest.mark.parametrize("speed_dps", [360.0, FAST_DPS])
def test_weak_wheel_heading_error_stays_under_five_percent_of_distance(speed_dps):
    rig = run_coupled(speed_dps)
    c = rig.chassis
    ratio = drift_ratio(rig.trace)
    worst_heading = max(abs(s.heading_deg) for s in rig.trace)
    assert ratio < 0.05, f"lateral drift reached {100 * ratio:.2f} % of distance"
    # Far inside the criterion, in fact: the heading loop wins the duty it needs.
    assert ratio < 0.005 and worst_heading < 0.5, (
        f"{100 * ratio:.3f} %, worst heading {worst_heading:.3f} deg"
    )
    assert c.x_mm == pytest.approx(DISTANCE_MM, abs=1.0), f"ended at {c.x_mm:.2f} mm"


@pytest.mark.parametrize("kp", [1.0, 3.0, 6.0])
def test_pure_p_control_fails_the_criterion_where_the_coupled_controller_passes(kp):
    coupled = drift_ratio(run_coupled(FAST_DPS).trace)
    pure_p = drift_ratio(run_pure_p(kp, FAST_DPS).trace)
    assert pure_p > 0.05, (
        f"pure P (kp={kp}) drifted only {100 * pure_p:.2f} %: the test no longer discriminates"
    )
    assert coupled < 0.05, f"coupled drifted {100 * coupled:.2f} %"
