"""The H-bridge core (firmware/native/hbridge.c) and a DC motor's IO (dc_motor_io.c), through the host
binding: the levels a signed duty puts on IN1/IN2/EN (what the hub's GPIO and LEDC carry), the
checks a bad frequency or duty meets, and a servo closing its loop over an encoder core and a bridge
joined in C, the IO a JGB37-520 or MG370 wheel gets on the firmware.
"""

import math

import pytest

from openbricks_native import HBridge, MotorIO, PCNTEncoder, Servo

from .plant import WheelPlant

DUTY_MAX = 65535  # a bridge with no pins keeps machine.PWM's duty_u16 scale
JGB37_CPR = 1320
JGB37_NO_LOAD_DPS = 1230.0


class TestLevels:
    def test_forward_reverse_brake_and_coast_put_the_datasheet_levels_on_the_pins(self):
        bridge = HBridge()
        assert bridge.levels() == (False, False, 0, DUTY_MAX) and bridge.state() == "coast"
        bridge.drive(50)
        assert bridge.levels() == (True, False, round(DUTY_MAX / 2), DUTY_MAX) and bridge.state() == "forward"
        bridge.drive(-25)
        assert bridge.levels() == (False, True, round(DUTY_MAX / 4), DUTY_MAX) and bridge.state() == "reverse"
        bridge.brake()
        assert bridge.levels() == (True, True, DUTY_MAX, DUTY_MAX) and bridge.state() == "brake"
        bridge.coast()
        assert bridge.levels() == (False, False, 0, DUTY_MAX) and bridge.state() == "coast"

    def test_zero_duty_brakes_the_way_a_controller_asks_to_stand_still(self):
        bridge = HBridge()
        bridge.drive(40)
        bridge.drive(0)
        assert bridge.state() == "brake" and bridge.duty() == 0.0

    def test_invert_swaps_the_direction_pins_not_the_duty(self):
        bridge = HBridge(invert=True)
        bridge.drive(30)
        assert bridge.levels()[:2] == (False, True) and steps(bridge) == pytest.approx(0.3 * DUTY_MAX, abs=1)
        assert bridge.state() == "reverse" and bridge.duty() == pytest.approx(30.0)
        bridge.brake()
        assert bridge.levels()[:2] == (True, True)

    @pytest.mark.parametrize(("duty", "expected"), [(250, 100.0), (-1e9, -100.0), (100.0, 100.0)])
    def test_duties_beyond_full_scale_are_clamped(self, duty, expected):
        bridge = HBridge()
        bridge.drive(duty)
        assert bridge.duty() == expected and bridge.levels()[2] == DUTY_MAX

    def test_the_pwm_duty_is_the_nearest_step_of_the_scale(self):
        bridge = HBridge()
        for duty in (0.001, 0.01, 33.3, 66.7, 99.999):
            bridge.drive(duty)
            # Within one step (the core works in single precision, as on the hub's FPU).
            assert steps(bridge) == pytest.approx(duty / 100 * DUTY_MAX, abs=1)
        bridge.drive(0.0001)
        assert steps(bridge) == 0 and bridge.state() == "forward"

    def test_a_repeated_duty_is_not_written_again(self):
        # The controller writes every millisecond, mostly the same duty: the pins hear only changes.
        bridge = HBridge()
        start = bridge.stats()[0]
        for _ in range(10):
            bridge.drive(20)
        bridge.drive(20.0001)  # the same step of the scale
        assert bridge.stats() == (start + 1, 0)
        bridge.drive(-20)
        assert bridge.stats() == (start + 2, 0)


class TestRefusals:
    @pytest.mark.parametrize("freq_hz", [0, 9, 100_001, 10**12])
    def test_a_frequency_no_bridge_runs_at_is_refused_with_the_range(self, freq_hz):
        with pytest.raises(ValueError, match=r"freq_hz must be 10\.\.100000"):
            HBridge(freq_hz=freq_hz)

    def test_the_frequency_must_be_an_int(self):
        with pytest.raises(TypeError, match="freq_hz must be an int"):
            HBridge(freq_hz=True)

    def test_the_host_has_no_pins_to_drive(self):
        assert HBridge.HARDWARE is False
        with pytest.raises(OSError, match="no LEDC"):
            HBridge(1, 2, 17)
        with pytest.raises(ValueError, match="all three pins"):
            HBridge(1, 2)

    @pytest.mark.parametrize("duty", [math.nan, math.inf, "50", None])
    def test_a_duty_that_is_not_a_finite_number_is_refused(self, duty):
        bridge = HBridge()
        with pytest.raises((TypeError, ValueError), match="duty_pct"):
            bridge.drive(duty)
        assert bridge.state() == "coast"

    def test_a_closed_bridge_coasts_and_refuses_commands(self):
        bridge = HBridge()
        bridge.drive(60)
        bridge.close()
        assert bridge.state() == "coast"
        with pytest.raises(ValueError, match="closed"):
            bridge.drive(10)
        bridge.close()  # again: nothing


class TestMotorIO:
    def test_the_io_reads_output_degrees_from_the_encoder_and_drives_the_bridge(self):
        bridge, encoder = HBridge(), PCNTEncoder(JGB37_CPR)
        io = bridge.motor_io(encoder, 360 / JGB37_CPR)
        assert isinstance(io, MotorIO)
        encoder.sample(0)
        encoder.sample(-330)
        assert io.read_angle() == pytest.approx(-90.0)
        io.write_duty(-70)
        assert bridge.levels()[:2] == (False, True) and steps(bridge) == pytest.approx(0.7 * DUTY_MAX, abs=1)
        io.write_duty(0)
        assert bridge.state() == "brake"
        io.coast()
        assert bridge.state() == "coast"

    def test_a_calibrated_fractional_scale_is_kept_exactly(self):
        # A calibrated MG370 at 68028.6 counts per turn, 73 turns out: the angle still reads to the count.
        bridge, encoder = HBridge(), PCNTEncoder(68028)
        io = bridge.motor_io(encoder, 360 / 68028.6)
        encoder.sample(0)
        encoder.reset(5_000_000)
        assert io.read_angle() == pytest.approx(5_000_000 * 360 / 68028.6, abs=1e-3)

    def test_the_io_refuses_what_is_not_an_open_encoder_or_a_scale(self):
        bridge, encoder = HBridge(), PCNTEncoder(JGB37_CPR)
        with pytest.raises(TypeError, match="open PCNTEncoder"):
            bridge.motor_io(object(), 1.0)
        with pytest.raises(ValueError, match="deg_per_count must be > 0"):
            bridge.motor_io(encoder, 0)
        encoder.close()
        with pytest.raises(TypeError, match="open PCNTEncoder"):
            bridge.motor_io(encoder, 1.0)

    def test_a_servo_over_the_io_runs_a_jgb37_to_its_target(self):
        plant = WheelPlant(no_load_speed_dps=JGB37_NO_LOAD_DPS, counts_per_rev=JGB37_CPR)
        bridge, encoder = HBridge(freq_hz=20_000), PCNTEncoder(JGB37_CPR)
        servo = Servo(
            io=bridge.motor_io(encoder, 360 / JGB37_CPR),
            counts_per_rev=JGB37_CPR,
            max_speed_dps=JGB37_NO_LOAD_DPS,
            ff_speed=100 / JGB37_NO_LOAD_DPS,
        )
        counter = PcntUnit()
        encoder.sample(counter.value)
        servo.run_target(600, 720, then="hold")
        for now in range(1, 4000):
            servo.tick(now)
            plant.step(duty_from_pins(bridge.levels()), 0.001)
            encoder.sample(counter.follow(round(plant.angle_deg * JGB37_CPR / 360)))
        assert servo.done()
        assert plant.angle_deg == pytest.approx(720, abs=1.0)


def steps(bridge):
    """EN's duty in steps of the bridge's scale."""
    return bridge.levels()[2]


class PcntUnit:
    """A PCNT unit at +-32767: counts every edge of a shaft and returns to 0 at either limit."""

    def __init__(self):
        self.value = 0
        self.total = 0

    def follow(self, total):
        value = self.value + total - self.total
        self.total = total
        self.value = int(math.fmod(value, 32767))
        return self.value


def duty_from_pins(levels):
    """The duty the motor sees from the bridge's levels (None: coasting, the winding open)."""
    in1, in2, duty, duty_max = levels
    if in1 and in2:
        return 0.0
    if in1 == in2 or duty == 0:
        return None
    return (100.0 if in1 else -100.0) * duty / duty_max
