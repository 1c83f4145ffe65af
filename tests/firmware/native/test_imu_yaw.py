"""The gyro heading integrator (imu_yaw core) on a simulated bench: a robot
whose true heading rate we choose, seen through a gyro with a bias, white
noise and jittery sample times, exactly as the hard tick feeds the core.
"""

import math
import random

import pytest

from openbricks_native import ImuYaw

BIAS_DPS = 0.7
NOISE_DPS = 0.08


class Bench:
    """A face-up gyro (Z counter-clockwise-positive) on a robot, sampled at about 1 kHz."""

    def __init__(
        self,
        yaw,
        *,
        bias_dps=BIAS_DPS,
        noise_dps=NOISE_DPS,
        scale=-1.0,
        period_us=1000,
        jitter_us=0,
        t0_us=0,
        seed=7,
    ):
        self.yaw = yaw
        self.bias_dps = bias_dps
        self.noise_dps = noise_dps
        self.scale = scale
        self.period_us = period_us
        self.jitter_us = jitter_us
        self.rng = random.Random(seed)
        self.t_us = t0_us
        self.true_heading_deg = 0.0
        self.rate_dps = 0.0
        yaw.update(self.gyro(0.0), self.t_us)

    def gyro(self, rate_dps):
        """What the sensor reads when the robot turns clockwise at rate_dps."""
        return rate_dps / self.scale + self.bias_dps + self.rng.gauss(0.0, self.noise_dps)

    def run(self, seconds, rate_of_t=lambda t_s: 0.0):
        """Drive the robot for `seconds` with heading rate rate_of_t(t) (CW-positive, deg/s)."""
        t_us = 0
        while t_us < seconds * 1e6:
            dt_us = self.period_us + self.rng.randint(-self.jitter_us, self.jitter_us)
            t_us += dt_us
            self.t_us += dt_us
            rate = rate_of_t(t_us / 1e6)
            self.true_heading_deg += 0.5 * (self.rate_dps + rate) * dt_us / 1e6
            self.rate_dps = rate
            self.yaw.update(self.gyro(rate), self.t_us)

    def rest(self, seconds):
        self.run(seconds)

    def turn(self, angle_deg, speed_dps=90.0, accel_dps2=360.0):
        """A trapezoidal in-place turn, as the drivebase plans it."""
        direction = math.copysign(1.0, angle_deg)
        ramp_s = speed_dps / accel_dps2
        cruise_s = abs(angle_deg) / speed_dps - ramp_s
        assert cruise_s >= 0, "turn too short for a trapezoid"
        total_s = 2 * ramp_s + cruise_s

        def rate(t_s):
            if t_s < ramp_s:
                return direction * accel_dps2 * t_s
            if t_s < ramp_s + cruise_s:
                return direction * speed_dps
            return direction * max(0.0, accel_dps2 * (total_s - t_s))

        self.run(total_s + 0.05, rate)

    def spin(self, seconds, rate_dps):
        self.run(seconds, lambda t_s: rate_dps)


# --- bias learning ------------------------------------------------------------------------------


def test_bias_is_learned_after_half_a_second_at_rest():
    yaw = ImuYaw()
    bench = Bench(yaw)
    bench.rest(0.4)
    assert not yaw.calibrated()
    bench.rest(0.6)
    assert yaw.calibrated()
    assert yaw.bias() == pytest.approx(BIAS_DPS, abs=0.02)


def test_a_robot_left_at_rest_keeps_its_heading():
    yaw = ImuYaw()
    bench = Bench(yaw)
    bench.rest(1.0)
    # The drift of the locking window itself is taken back: the robot did not turn.
    assert abs(yaw.heading()) < 0.02
    bench.rest(20.0)
    # Uncorrected, a 0.7 deg/s bias would have turned this into 14 degrees.
    assert abs(yaw.heading()) < 0.1


def test_bias_is_not_learned_while_turning():
    yaw = ImuYaw()
    bench = Bench(yaw)
    bench.rest(1.0)
    learned = yaw.bias()
    bench.spin(5.0, 90.0)
    bench.spin(5.0, -3.0)  # a slow crawl, just outside the stillness band
    assert yaw.bias() == learned


def test_a_steady_turn_at_boot_is_not_taken_for_bias():
    yaw = ImuYaw()
    bench = Bench(yaw)
    bench.spin(3.0, 30.0)  # perfectly steady, so only its size gives it away
    assert not yaw.calibrated()
    assert yaw.bias() == 0.0


def test_bias_follows_slow_thermal_drift_at_rest():
    yaw = ImuYaw()
    bench = Bench(yaw, bias_dps=0.5)
    bench.rest(1.0)
    bench.bias_dps = 0.8
    bench.rest(60.0)
    assert yaw.bias() == pytest.approx(0.8, abs=0.03)


# --- integration ----------------------------------------------------------------------------------


def test_a_90_degree_turn_with_a_biased_noisy_jittery_gyro():
    yaw = ImuYaw()
    bench = Bench(yaw, jitter_us=300)
    bench.rest(1.0)
    bench.turn(90.0)
    bench.rest(1.0)
    assert bench.true_heading_deg == pytest.approx(90.0, abs=0.01)
    assert yaw.heading() == pytest.approx(90.0, abs=0.1)


def test_heading_is_clockwise_positive():
    face_up = ImuYaw()
    bench = Bench(face_up, bias_dps=0.0, noise_dps=0.0)
    bench.spin(1.0, 45.0)
    assert face_up.heading() == pytest.approx(bench.true_heading_deg, abs=0.01)
    assert face_up.heading() == pytest.approx(45.0, abs=0.05)
    assert face_up.rate() == pytest.approx(45.0, abs=1e-3)

    # A face-up gyro reads a clockwise turn as negative Z.
    raw = ImuYaw()
    raw.update(0.0, 0)
    raw.update(10.0, 100_000)
    assert raw.heading() < 0

    face_down = ImuYaw(scale=1.0)
    face_down.update(0.0, 0)
    face_down.update(10.0, 100_000)
    assert face_down.heading() > 0


def test_heading_unwraps_past_plus_and_minus_180():
    yaw = ImuYaw()
    bench = Bench(yaw)
    bench.rest(1.0)
    bench.spin(6.0, 180.0)
    assert yaw.heading() == pytest.approx(1080.0, abs=0.2)
    bench.spin(10.0, -180.0)
    assert yaw.heading() == pytest.approx(-720.0, abs=0.3)


def test_a_long_spin_keeps_its_precision():
    yaw = ImuYaw()
    yaw.seed_bias(0.0)
    bench = Bench(yaw, bias_dps=0.0, noise_dps=0.0)
    bench.spin(100.0, 360.0)  # a hundred turns at 1 kHz: 100 000 small increments
    # A plain float running sum ends about 27 degrees short here.
    assert yaw.heading() == pytest.approx(bench.true_heading_deg, abs=0.05)


def test_time_is_taken_from_the_sample_clock():
    yaw = ImuYaw()
    yaw.seed_bias(0.0)
    rng = random.Random(3)
    t_us = 0
    yaw.update(-90.0, t_us)
    while t_us < 2_000_000:
        t_us += rng.randint(200, 3000)  # late and early samples
        yaw.update(-90.0, t_us)
    assert yaw.heading() == pytest.approx(90.0 * t_us / 1e6, abs=0.01)


def test_the_microsecond_clock_may_wrap():
    yaw = ImuYaw()
    bench = Bench(yaw, t0_us=2**32 - 300_000)  # wraps 0.3 s in
    bench.rest(1.0)
    bench.turn(90.0)
    assert bench.t_us > 2**32
    assert yaw.heading() == pytest.approx(90.0, abs=0.1)


def test_a_silent_gap_is_not_integrated():
    yaw = ImuYaw()
    yaw.seed_bias(0.0)
    yaw.update(-90.0, 0)
    yaw.update(-90.0, 10_000)  # 0.9 deg
    yaw.update(-90.0, 510_000)  # half a second of silence: motion unknown
    yaw.update(-90.0, 520_000)  # 0.9 deg
    assert yaw.heading() == pytest.approx(1.8, abs=1e-4)


# --- persisted calibration ------------------------------------------------------------------------


def test_a_seeded_bias_corrects_from_the_first_sample():
    seeded = ImuYaw()
    seeded.seed_bias(BIAS_DPS)
    assert seeded.calibrated()
    bench = Bench(seeded)
    bench.turn(90.0)  # straight from boot, no time to learn
    assert seeded.heading() == pytest.approx(90.0, abs=0.1)

    unseeded = ImuYaw()
    Bench(unseeded).turn(90.0)
    assert abs(unseeded.heading() - 90.0) > 0.5


@pytest.mark.parametrize("bad", [math.nan, math.inf, 50.0, -5.5])
def test_a_corrupt_stored_bias_is_refused(bad):
    yaw = ImuYaw()
    with pytest.raises(ValueError, match="stored calibration looks corrupt"):
        yaw.seed_bias(bad)
    assert not yaw.calibrated()
    assert yaw.bias() == 0.0


def test_reset_heading_keeps_the_bias():
    yaw = ImuYaw()
    bench = Bench(yaw)
    bench.rest(1.0)
    bench.turn(90.0)
    learned = yaw.bias()
    yaw.reset_heading()
    assert yaw.heading() == 0.0
    assert yaw.calibrated() and yaw.bias() == learned
    bench.rest(5.0)
    assert abs(yaw.heading()) < 0.05
    yaw.reset_heading(-30.0)
    bench.turn(30.0)
    assert yaw.heading() == pytest.approx(0.0, abs=0.1)


def test_reset_during_the_boot_window_is_not_undone_by_the_lock():
    yaw = ImuYaw()
    bench = Bench(yaw)
    bench.rest(0.3)
    yaw.reset_heading(10.0)
    bench.rest(0.7)  # the lock lands after the reset
    assert yaw.calibrated()
    assert yaw.heading() == pytest.approx(10.0, abs=0.05)


# --- configuration --------------------------------------------------------------------------------


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        ({"scale": 0.0}, "scale must be non-zero"),
        ({"scale": math.nan}, "scale must be a finite number"),
        ({"still_band_dps": 0.0}, "still_band_dps must be in"),
        ({"settle_ms": -1}, "settle_ms must be in 0..60000"),
        ({"track_tau_s": 0.0}, "track_tau_s must be in"),
        ({"max_bias_dps": -1.0}, "max_bias_dps must be in"),
    ],
)
def test_bad_configuration_is_refused_by_name(kwargs, message):
    with pytest.raises(ValueError, match=message):
        ImuYaw(**kwargs)


def test_a_longer_settle_window_delays_the_lock():
    yaw = ImuYaw(settle_ms=2000)
    bench = Bench(yaw)
    bench.rest(1.5)
    assert not yaw.calibrated()
    bench.rest(1.0)
    assert yaw.calibrated()


@pytest.mark.parametrize("garbled", [math.nan, math.inf, -math.inf])
def test_a_garbled_sample_is_dropped_like_a_missed_one(garbled):
    yaw = ImuYaw()
    yaw.seed_bias(0.0)
    yaw.update(-90.0, 0)
    yaw.update(garbled, 5_000)
    yaw.update(-90.0, 10_000)  # integrates the whole 10 ms
    assert yaw.heading() == pytest.approx(0.9, abs=1e-4)
    assert math.isfinite(yaw.rate())
