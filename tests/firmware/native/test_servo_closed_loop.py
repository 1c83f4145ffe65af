"""The servo core closing the loop around WheelPlant at 1 kHz, through the binding's direct path."""

from __future__ import annotations

import numpy as np
import pytest

from openbricks_native import Servo

from .plant import WheelPlant


class Rig:
    """One servo driving one plant: read the encoder, update, apply the duty for 1 ms."""

    def __init__(self, servo: Servo | None = None, **plant_kwargs):
        self.plant = WheelPlant(**plant_kwargs)
        self.servo = servo or Servo()
        self.now_ms = 0
        self.silent = False
        self.trace: list[tuple[int, float, float, float | None]] = []
        self.run(1)

    def run(self, ms: int, until=None) -> None:
        for _ in range(ms):
            self.now_ms += 1
            reading = None if self.silent else self.plant.encoder_deg
            duty = self.servo.update(self.now_ms, reading)
            self.trace.append((self.now_ms, self.plant.angle_deg, self.plant.speed_dps, duty))
            self.plant.step(duty, 0.001)
            if until is not None and until():
                return

    def window(self, ms: int) -> np.ndarray:
        """The last ms rows of (t, angle, speed, duty) with coasting as NaN duty."""
        rows = self.trace[-ms:]
        return np.array([(t, x, v, np.nan if d is None else d) for t, x, v, d in rows])


class TestSpeed:
    @pytest.mark.parametrize("speed_dps", [60.0, 400.0, -700.0])
    def test_run_speed_tracks_within_two_percent(self, speed_dps):
        rig = Rig()
        rig.servo.run_speed(speed_dps)
        rig.run(1000)
        rows = rig.window(500)
        mean = rows[:, 2].mean()
        assert mean == pytest.approx(speed_dps, rel=0.02), f"mean {mean:.1f} deg/s for {speed_dps}"
        assert rows[:, 2].std() < 0.03 * abs(speed_dps) + 3.0, f"ripple {rows[:, 2].std():.1f} deg/s"
        assert not rig.servo.stalled() and not rig.servo.done()

    def test_weak_wheel_still_reaches_speed(self):
        # 90 % torque and five times the friction: feed-forward alone falls short, the loop makes it up.
        rig = Rig(effectiveness=0.9, coulomb_nm=0.05, static_nm=0.06)
        rig.servo.run_speed(500)
        rig.run(1500)
        assert rig.window(500)[:, 2].mean() == pytest.approx(500.0, rel=0.02)

    def test_ramps_at_the_set_acceleration(self):
        rig = Rig()
        rig.servo.settings(accel_dps2=1000.0)
        rig.servo.run_speed(500)
        rig.run(250)
        speed = rig.plant.speed_dps
        assert speed == pytest.approx(250.0, abs=30.0), f"{speed:.0f} deg/s after 0.25 s at 1000 deg/s^2"

    def test_speed_change_while_running_is_smooth(self):
        rig = Rig()
        rig.servo.run_speed(600)
        rig.run(800)
        rig.servo.run_speed(-200)
        rig.run(1200)
        speeds = rig.window(1200)[:, 2]
        steps = np.abs(np.diff(speeds))
        assert steps.max() < 10.0, "no jolt larger than the 1500 deg/s^2 ramp allows per ms"
        assert speeds[-300:].mean() == pytest.approx(-200.0, rel=0.02)


class TestPosition:
    @pytest.mark.parametrize(
        ("speed_dps", "target_deg"), [(500, 360.0), (300, -90.0), (800, 1440.0), (200, 4.0)]
    )
    def test_run_target_lands_within_a_degree_without_overshoot(self, speed_dps, target_deg):
        rig = Rig()
        rig.servo.run_target(speed_dps, target_deg, then="hold")
        rig.run(6000, until=rig.servo.done)
        assert rig.servo.done(), "the move finished"
        rig.run(300)
        angles = rig.window(len(rig.trace))[:, 1]
        overshoot = (angles - target_deg).max() if target_deg > 0 else (target_deg - angles).max()
        assert overshoot < 1.0, f"overshot by {overshoot:.2f} deg"
        assert rig.plant.angle_deg == pytest.approx(target_deg, abs=1.0)

    def test_move_finishes_on_the_profile_schedule(self):
        rig = Rig()
        rig.servo.run_target(500, 720, then="hold")
        start = rig.now_ms
        rig.run(5000, until=rig.servo.done)
        expected_ms = (720 / 500 + 500 / 1500) * 1000
        assert rig.now_ms - start == pytest.approx(expected_ms, abs=80)

    def test_chained_run_angle_adds_up_exactly(self):
        rig = Rig()
        for _ in range(8):
            rig.servo.run_angle(400, 45, then="hold")
            rig.run(3000, until=rig.servo.done)
        rig.run(300)
        assert rig.plant.angle_deg == pytest.approx(360.0, abs=0.5)

    def test_run_angle_direction_rule(self):
        rig = Rig()
        rig.servo.run_angle(-300, 90, then="hold")  # negative speed: backwards
        rig.run(3000, until=rig.servo.done)
        rig.servo.run_angle(-300, -30, then="hold")  # both negative: forwards
        rig.run(3000, until=rig.servo.done)
        rig.run(200)
        assert rig.plant.angle_deg == pytest.approx(-60.0, abs=1.0)

    def test_then_coast_and_brake_release_the_hold(self):
        for then, expected in (("coast", None), ("stop", None), ("brake", 0.0)):
            rig = Rig()
            rig.servo.run_target(400, 180, then=then)
            rig.run(3000, until=rig.servo.done)
            rig.run(5)
            assert rig.servo.duty == expected, then
            assert rig.servo.state()["mode"] == ("brake" if then == "brake" else "coast")
            assert rig.plant.angle_deg == pytest.approx(180.0, abs=1.5)

    def test_then_continue_passes_the_target_at_cruise(self):
        rig = Rig()
        rig.servo.run_target(400, 360, then="continue")
        rig.run(3000, until=rig.servo.done)
        assert rig.plant.angle_deg == pytest.approx(360.0, abs=5.0)
        assert rig.plant.speed_dps == pytest.approx(400.0, rel=0.05), "still at cruise when done"
        rig.run(500)
        assert rig.window(300)[:, 2].mean() == pytest.approx(400.0, rel=0.03)

    def test_new_move_from_a_running_one_joins_without_a_jolt(self):
        rig = Rig()
        rig.servo.run_speed(500)
        rig.run(600)
        here = rig.plant.angle_deg
        rig.servo.run_target(500, here + 100, then="hold")
        rig.run(2000, until=rig.servo.done)
        rig.run(200)
        speeds = rig.window(len(rig.trace) - 600)[:, 2]
        assert np.abs(np.diff(speeds)).max() < 12.0
        assert rig.plant.angle_deg == pytest.approx(here + 100, abs=1.0)


class TestHold:
    def test_hold_resists_a_disturbance_and_recovers(self):
        rig = Rig()
        rig.servo.hold()
        rig.run(100)
        rig.plant.load_torque_nm = 0.3  # about 30 % of stall torque, pushing forwards
        rig.run(300)
        deflection = np.abs(rig.window(300)[:, 1]).max()
        assert deflection < 3.0, f"gave way by {deflection:.2f} deg"
        assert abs(rig.plant.angle_deg) < 0.5, "the integrator pulls it back under the steady load"
        rig.plant.load_torque_nm = 0.0
        rig.run(500)
        assert abs(rig.plant.angle_deg) < 0.5, "and lets go of the correction once the load is gone"

    def test_reset_angle_while_holding_does_not_move_the_shaft(self):
        rig = Rig()
        rig.servo.run_target(400, 90, then="hold")
        rig.run(2000, until=rig.servo.done)
        rig.run(100)
        before = rig.plant.angle_deg
        rig.servo.reset_angle(0)
        rig.run(300)
        assert rig.plant.angle_deg == pytest.approx(before, abs=0.3)
        assert rig.servo.angle() == pytest.approx(0.0, abs=0.3)
        rig.servo.run_target(400, 90, then="hold")
        rig.run(2000, until=rig.servo.done)
        rig.run(200)
        assert rig.plant.angle_deg == pytest.approx(before + 90, abs=1.0)


class TestStall:
    def test_blocked_wheel_is_reported_stalled(self):
        rig = Rig()
        rig.servo.run_speed(300)
        rig.run(500)
        assert not rig.servo.stalled(), "running freely"
        rig.plant.blocked = True
        rig.run(150)
        assert not rig.servo.stalled(), "not before the stall window"
        rig.run(400, until=rig.servo.stalled)
        assert rig.servo.stalled()
        duty = rig.servo.duty
        assert duty == pytest.approx(100.0), "pushing as hard as allowed, not winding beyond it"
        rig.plant.blocked = False
        rig.run(300)
        assert not rig.servo.stalled()
        speeds = rig.window(150)[:, 2]
        assert speeds.max() < 300 * 1.15, "released without racing to catch up"

    def test_move_into_a_block_finishes_as_stalled(self):
        rig = Rig()
        rig.servo.run_target(300, 360, then="coast")
        rig.run(300)
        rig.plant.blocked = True
        rig.run(4000, until=rig.servo.done)
        assert rig.servo.done() and rig.servo.stalled()
        rig.run(2)
        assert rig.servo.duty is None, "then='coast' applied"

    def test_move_after_a_stall_starts_from_where_the_shaft_is(self):
        rig = Rig()
        rig.servo.run_target(300, 360, then="hold")
        rig.run(300)
        rig.plant.blocked = True
        rig.run(4000, until=rig.servo.done)
        stuck_at = rig.plant.angle_deg
        assert stuck_at < 100.0 and rig.servo.stalled()
        rig.servo.run_angle(300, 30, then="hold")  # relative to the shaft, not to the unreached 360
        rig.plant.blocked = False
        rig.run(3000, until=rig.servo.done)
        rig.run(200)
        assert rig.plant.angle_deg == pytest.approx(stuck_at + 30.0, abs=1.0)

    def test_duty_limit_caps_output_and_still_detects_the_stall(self):
        rig = Rig()
        rig.servo.set_duty_limit(25)
        rig.servo.run_speed(300)  # needs about 35 % duty: the cap binds, and it is not a stall
        rig.run(800)
        rows = rig.window(800)
        assert np.nanmax(np.abs(rows[:, 3])) <= 25.0
        assert not rig.servo.stalled(), f"slow ({rows[-1, 2]:.0f} deg/s) but moving is not stalled"
        rig.plant.blocked = True
        rig.run(600, until=rig.servo.stalled)
        assert rig.servo.stalled()
        assert rig.servo.duty == pytest.approx(25.0)
        rig.servo.set_duty_limit(None)
        assert rig.servo.duty_limit == 100.0

    def test_duty_limit_applies_to_dc(self):
        rig = Rig()
        rig.servo.set_duty_limit(40)
        rig.servo.dc(-90)
        rig.run(10)
        assert rig.servo.duty == -40.0


class TestSilentFeedback:
    def test_short_gap_holds_output_and_resumes(self):
        rig = Rig()
        rig.servo.run_speed(400)
        rig.run(600)
        before = rig.servo.duty
        rig.silent = True
        rig.run(10)
        assert rig.servo.duty == before, "a dropped reading keeps the last output"
        rig.silent = False
        rig.run(400)
        assert not rig.servo.state()["feedback_lost"]
        assert rig.window(200)[:, 2].mean() == pytest.approx(400.0, rel=0.02)
        assert rig.servo.failed_reads == 10

    def test_silent_feedback_halts_without_windup(self):
        rig = Rig()
        rig.servo.run_target(500, 3600, then="hold")
        rig.run(500)
        rig.silent = True
        rig.run(19)
        assert rig.servo.duty is not None
        rig.run(1)
        assert rig.servo.duty is None, "coasts once silent for 20 ms"
        assert rig.servo.feedback_lost and rig.servo.done()
        assert rig.servo.state()["silent_reads"] == 20
        rig.run(500)
        rig.silent = False
        rig.run(300)
        duties = rig.window(300)[:, 3]
        assert np.all(np.isnan(duties)), "no surge when the readings come back: it stays released"
        assert rig.servo.failed_reads == 520
        # A new command clears the fault and starts from where the wheel really is.
        here = rig.plant.angle_deg
        rig.servo.run_target(300, here + 30, then="hold")
        assert not rig.servo.feedback_lost
        rig.run(2000, until=rig.servo.done)
        rig.run(100)
        assert rig.plant.angle_deg == pytest.approx(here + 30, abs=1.0)

    def test_command_before_first_reading_waits_for_it(self):
        rig = Rig(angle_deg=100.0)
        servo = Servo()
        rig.servo = servo
        servo.run_angle(300, 45, then="hold")
        rig.run(2000, until=servo.done)
        rig.run(100)
        assert rig.plant.angle_deg == pytest.approx(145.0, abs=1.0)


class TestResumeAfterGap:
    """A servo that stops being ticked (the runtime unsubscribes a wheel's servo while a drive base
    drives that wheel) and is commanded again right after it is subscribed once more."""

    @staticmethod
    def idle_while_turned_elsewhere(rig: Rig, turned_deg: float, gap_ms: int) -> float:
        rig.servo.coast()
        rig.plant.angle_deg += turned_deg
        rig.now_ms += gap_ms
        return rig.plant.angle_deg

    def test_run_angle_after_a_gap_moves_from_where_the_wheel_is_now(self):
        rig = Rig()
        rig.servo.run_angle(360, 90, then="hold")
        rig.run(1500, until=rig.servo.done)
        here = self.idle_while_turned_elsewhere(rig, 1000.0, 5000)
        resumed_at = len(rig.trace)
        rig.servo.run_angle(360, 90, then="hold")
        rig.run(20)
        first = rig.window(20)
        assert np.nanmax(np.abs(first[:, 3])) < 30.0, f"kick of {np.nanmax(np.abs(first[:, 3])):.0f} % duty"
        rig.run(2000, until=rig.servo.done)
        rig.run(200)
        angles = rig.window(len(rig.trace) - resumed_at)[:, 1]
        assert angles.min() > here - 1.0, f"ran back to {angles.min():.0f} deg from {here:.0f}"
        assert rig.plant.angle_deg == pytest.approx(here + 90.0, abs=1.0)

    def test_run_speed_after_a_gap_ramps_up_from_rest(self):
        rig = Rig()
        rig.run(100)
        self.idle_while_turned_elsewhere(rig, 300.0, 3000)
        rig.servo.run_speed(500)
        rig.run(100)
        speed = rig.plant.speed_dps
        assert speed == pytest.approx(150.0, abs=30.0), f"{speed:.0f} deg/s after 0.1 s at 1500 deg/s^2"

    def test_speed_estimate_after_a_stalled_caller_follows_the_motor(self):
        # A long GC pause: no tick for 300 ms while the released motor slowed down. The first
        # readings afterwards must give the speed the motor has, not a spike from a stale prediction.
        rig = Rig()
        rig.servo.run_speed(500)
        rig.run(800)
        for _ in range(300):
            rig.plant.step(None, 0.001)
            rig.now_ms += 1
        errors = []
        for _ in range(30):
            rig.run(1)
            errors.append(abs(rig.servo.speed() - rig.plant.speed_dps))
        assert max(errors) < 100.0, f"speed estimate off by up to {max(errors):.0f} deg/s"

    def test_a_command_repeated_after_a_stalled_caller_keeps_the_motor_running_smoothly(self):
        # A loop re-issuing run_speed() on the hub, and a 40 ms GC pause just before one call: the
        # motor kept its duty meanwhile and is still at speed, which the new plan must start from.
        rig = Rig()
        rig.servo.run_speed(500)
        rig.run(800)
        cruise = rig.servo.duty
        for _ in range(40):
            rig.plant.step(cruise, 0.001)
            rig.now_ms += 1
        rig.servo.run_speed(500)
        rig.run(100)
        duties = rig.window(100)[:, 3]
        assert np.abs(duties - cruise).max() < 10.0, f"duty jumped by {np.abs(duties - cruise).max():.0f} %"
        assert rig.window(50)[:, 2].mean() == pytest.approx(500.0, rel=0.02)

    def test_a_late_tick_keeps_the_profile_schedule(self):
        # Shorter than silent_timeout_ms: a late tick, not a gap; the move keeps its clock.
        rig = Rig()
        rig.servo.run_target(500, 720, then="hold")
        start = rig.now_ms
        rig.now_ms += 15
        rig.run(5000, until=rig.servo.done)
        expected_ms = (720 / 500 + 500 / 1500) * 1000
        assert rig.now_ms - start == pytest.approx(expected_ms, abs=80)


class TestCallableIO:
    def test_callables_carry_the_loop(self):
        plant = WheelPlant()
        out = {"duty": None}
        servo = Servo(
            read_angle=lambda: plant.encoder_deg,
            write_duty=lambda d: out.__setitem__("duty", d),
            write_coast=lambda: out.__setitem__("duty", None),
        )
        servo.run_target(400, 200, then="brake")
        for now in range(1, 3000):
            servo.tick(now)
            plant.step(out["duty"], 0.001)
        assert plant.angle_deg == pytest.approx(200.0, abs=1.0)
        assert out["duty"] == 0.0

    def test_read_angle_returning_none_counts_as_a_failed_read(self):
        servo = Servo(read_angle=lambda: None, write_duty=lambda d: None, write_coast=lambda: None)
        servo.run_speed(100)
        for now in range(1, 40):
            servo.tick(now)
        assert servo.failed_reads == 39
        assert servo.feedback_lost

    def test_bad_read_value_raises_and_counts(self):
        servo = Servo(read_angle=lambda: "12", write_duty=lambda d: None, write_coast=lambda: None)
        with pytest.raises(TypeError, match="the value returned by read_angle must be a number"):
            servo.tick(1)
        assert servo.failed_reads == 1


class TestValidation:
    def test_then_must_be_a_manual_value(self):
        with pytest.raises(
            ValueError, match="then must be one of 'coast', 'stop', 'brake', 'hold', 'continue'"
        ):
            Servo().run_target(100, 10, then="park")

    def test_unknown_setting_lists_the_valid_ones(self):
        with pytest.raises(TypeError, match="unknown setting 'kpp'; the settings are: kp, ki"):
            Servo(kpp=1.0)

    @pytest.mark.parametrize(
        ("call", "message"),
        [
            (lambda s: s.dc(120), "duty_pct must be within -100..100"),
            (lambda s: s.run_target(0, 10), "speed_dps must not be 0"),
            (lambda s: s.run_speed(float("nan")), "speed_dps must be a finite number"),
            (lambda s: s.set_duty_limit(0), r"limit_pct must be within \(0, 100\]"),
            (lambda s: s.settings(accel_dps2=0), "accel_dps2 must be > 0"),
            (lambda s: s.run_angle(100, 10, accel_dps2=-1), "accel_dps2 must be > 0"),
            (lambda s: s.update(-5, 0.0), "now_ms must be within"),
        ],
    )
    def test_bad_values_name_the_argument(self, call, message):
        with pytest.raises(ValueError, match=message):
            call(Servo())

    def test_io_must_be_complete(self):
        with pytest.raises(TypeError, match="give all of read_angle, write_duty and write_coast"):
            Servo(read_angle=lambda: 0.0)

    def test_numpy_scalars_are_numbers_but_float_times_are_not(self):
        servo = Servo()
        servo.update(np.int64(1), np.float32(1.5))
        assert servo.angle() == 1.5
        with pytest.raises(TypeError, match="now_ms must be an int"):
            servo.update(2.0, 1.5)

    def test_settings_round_trip(self):
        servo = Servo(kp=5.0, stall_time_ms=150)
        values = servo.settings()
        assert values["kp"] == 5.0 and values["stall_time_ms"] == 150
        assert servo.settings(speed_kp=0.4)["speed_kp"] == pytest.approx(0.4)
