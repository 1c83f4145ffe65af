"""The Pybricks conveniences every motor inherits from the Motor contract.

They are exercised on a small shaft model (ideal speed tracking, an optional
end stop) so the assertions are about where the shaft ends up and how the
motor is left, as a user sees it.
"""

import time

from fakes.expect import approx, raises
from openbricks.interfaces import IMU, ColorSensor, Motor, Servo
from openbricks.parameters import Stop


class _ShaftModel(Motor):
    """Tracks commanded speed exactly until the shaft meets `end_stop_deg`."""

    def __init__(self, end_stop_deg=None, slow_start_ms=0):
        self._angle = 0.0
        self._speed = 0.0
        self._since = time.ticks_ms()
        self._run_started = None
        self.end_stop_deg = end_stop_deg
        self.slow_start_ms = slow_start_ms  # reads "stalled" this long after each start
        self.state = "coast"
        self.duty_limit = 100
        self.duty_limits_seen = []
        self.run_angle_calls = []

    def _advance(self):
        now = time.ticks_ms()
        self._angle += self._speed * time.ticks_diff(now, self._since) / 1000
        self._since = now
        if self.end_stop_deg is not None and self._angle >= self.end_stop_deg:
            self._angle = self.end_stop_deg

    def run_speed(self, deg_per_s):
        self._advance()
        self._speed = deg_per_s
        self._run_started = time.ticks_ms()
        self.state = "run"
        self.duty_limits_seen.append(self.duty_limit)

    def _halt(self, state):
        self._advance()
        self._speed = 0.0
        self.state = state

    def coast(self):
        self._halt("coast")

    def brake(self):
        self._halt("brake")

    def hold(self):
        self._halt("hold")

    def angle(self):
        self._advance()
        return self._angle

    def reset_angle(self, angle=0):
        self._advance()
        self._angle = angle

    def run_angle(self, deg_per_s, target_angle, wait=True, then=Stop.COAST):
        self.run_angle_calls.append((deg_per_s, target_angle, wait, then))

    def stalled(self):
        self._advance()
        if self._speed == 0:
            return False
        if time.ticks_diff(time.ticks_ms(), self._run_started) < self.slow_start_ms:
            return True
        return self.end_stop_deg is not None and self._angle >= self.end_stop_deg

    def _duty_limit_push(self, limit_pct):
        self._saved_limit = self.duty_limit
        self.duty_limit = limit_pct

    def _duty_limit_pop(self):
        self.duty_limit = self._saved_limit


class _BareMotor(Motor):
    def coast(self):
        pass


def test_run_is_closed_loop_speed_and_stop_coasts():
    m = _ShaftModel()
    m.run(180)
    time.sleep_ms(500)
    assert approx(m.angle(), 90, 0.5)
    m.stop()
    assert m.state == "coast"


def test_run_time_runs_for_the_duration_then_holds_by_default():
    m = _ShaftModel()
    start = time.ticks_ms()
    m.run_time(360, 1500)
    assert time.ticks_diff(time.ticks_ms(), start) == 1500
    assert approx(m.angle(), 540, 0.5)
    assert m.state == "hold"


def test_run_time_then_continue_leaves_the_motor_running():
    m = _ShaftModel()
    m.run_time(100, 200, then=Stop.NONE)
    assert m.state == "run"
    m.run_time(100, 200, then="brake")
    assert m.state == "brake"


def test_run_time_refuses_wait_false_and_bad_end_states_before_moving():
    m = _ShaftModel()
    with raises(ValueError, "run_time(wait=False) is not supported"):
        m.run_time(100, 200, wait=False)
    with raises(ValueError, "is not an end state"):
        m.run_time(100, 200, then="park")
    with raises(ValueError, "must be >= 0 ms"):
        m.run_time(100, -5)
    assert m.state == "coast"
    assert m.angle() == 0


def test_run_target_moves_by_the_difference_from_the_current_angle():
    m = _ShaftModel()
    m.reset_angle(90)
    m.run_target(-200, 0)
    assert m.run_angle_calls == [(200, -90, True, "hold")]
    m.run_target(300, 450, then="coast", wait=False)
    assert m.run_angle_calls[-1] == (300, 360, False, "coast")


def test_run_until_stalled_returns_the_end_stop_angle_and_applies_then():
    m = _ShaftModel(end_stop_deg=123)
    stall_angle = m.run_until_stalled(200, then="hold")
    assert approx(stall_angle, 123, 1e-6)
    assert m.state == "hold"


def test_run_until_stalled_ignores_the_brief_stall_reading_of_a_start_from_rest():
    m = _ShaftModel(end_stop_deg=300, slow_start_ms=Motor.STALL_CONFIRM_MS // 2)
    assert approx(m.run_until_stalled(400), 300, 1e-6)
    assert m.state == "coast"


def test_run_until_stalled_caps_the_duty_during_the_run_and_restores_it():
    m = _ShaftModel(end_stop_deg=45)
    m.run_until_stalled(100, duty_limit=30)
    assert m.duty_limits_seen == [30]
    assert m.duty_limit == 100


def test_run_until_stalled_restores_the_duty_cap_when_the_run_fails():
    m = _ShaftModel(end_stop_deg=45)

    def silent_bus():
        raise OSError("motor is not responding on the bus")

    m.stalled = silent_bus
    with raises(OSError, "not responding"):
        m.run_until_stalled(100, duty_limit=20)
    assert m.duty_limit == 100


def test_run_until_stalled_validates_duty_limit():
    m = _ShaftModel(end_stop_deg=45)
    with raises(ValueError, "0 < duty_limit <= 100"):
        m.run_until_stalled(100, duty_limit=0)
    with raises(ValueError, "0 < duty_limit <= 100"):
        m.run_until_stalled(100, duty_limit=150)
    assert m.state == "coast"


def test_duty_limit_on_a_motor_without_a_torque_cap_is_refused_up_front():
    with raises(NotImplementedError, "_BareMotor does not support run_until_stalled(duty_limit=...)"):
        _BareMotor().run_until_stalled(100, duty_limit=50)


def test_missing_capabilities_name_the_driver_and_what_to_use_instead():
    m = _BareMotor()
    with raises(NotImplementedError, "_BareMotor does not support hold(); it has no position control"):
        m.hold()
    with raises(NotImplementedError, "use dc(duty)"):
        m.run(100)
    with raises(NotImplementedError, "_BareMotor does not support angle()"):
        m.angle()
    assert m.done() is True


def test_other_contracts_name_the_driver_when_a_method_is_missing():
    class Gyro(IMU):
        pass

    class Eye(ColorSensor):
        pass

    class Arm(Servo):
        pass

    with raises(NotImplementedError, "Gyro does not support heading()"):
        Gyro().heading()
    with raises(NotImplementedError, "Eye does not support rgb()"):
        Eye().rgb()
    with raises(NotImplementedError, "Arm does not support move_to()"):
        Arm().move_to(90)
