"""JGB37-520 closed loop on the native servo core, against a geared-DC-motor plant on the fake board."""

import time

import _openbricks_native
import machine

from fakes.dc_motor import DCMotorRig, QuadratureLines
from fakes.expect import approx
from openbricks import pins
from openbricks.drivers.jgb37_520 import JGB37Motor
from tests.firmware.native.plant import KG_CM_TO_NM, WheelPlant

NEEDS_NATIVE = True


def _plant():
    # A 12 V JGB37-520 1:30 on a 2S pack driving a 65 mm wheel of a 1 kg robot.
    return WheelPlant(
        no_load_speed_dps=1230.0,
        stall_torque_nm=2.5 * KG_CM_TO_NM,
        gear_ratio=30.0,
        rotor_inertia_kgm2=6.0e-7,
        wheel_diameter_mm=65.0,
        coulomb_nm=0.004,
        static_nm=0.006,
        counts_per_rev=1320,
    )


def _rig(invert=False):
    pins.reset_claims()
    _openbricks_native.motor_process.reset()
    plant = _plant()
    lines = QuadratureLines(7, 8)
    rig = DCMotorRig(plant, in1=1, in2=2, pwm=17, counts_per_rev=1320, encoder=lines)
    motor = JGB37Motor(in1=1, in2=2, pwm=17, encoder_a=7, encoder_b=8, invert=invert)
    tick = machine.Timer(0)
    tick.init(freq=1000, callback=lambda _t: _openbricks_native.motor_process.tick(time.ticks_ms()))
    return motor, plant, rig


def test_run_angle_two_turns_lands_on_target_and_coasts():
    motor, plant, rig = _rig()
    start = time.ticks_ms()
    motor.run_angle(360, 720)
    elapsed_ms = time.ticks_diff(time.ticks_ms(), start)
    assert 1900 < elapsed_ms < 3000  # 2 s at cruise plus the ramps
    assert approx(plant.angle_deg, 720, 2)
    assert approx(motor.angle(), plant.encoder_deg, 0.3)
    assert motor.done()
    time.sleep_ms(20)
    assert rig.bridge_duty() is None  # then="coast" released the bridge


def test_run_speed_holds_the_speed_and_speed_reads_it():
    motor, plant, _ = _rig()
    motor.run(300)
    time.sleep_ms(1000)
    assert approx(plant.speed_dps, 300, 15)
    assert approx(motor.speed(), 300, 15)
    motor.brake()
    time.sleep_ms(300)
    assert abs(plant.speed_dps) < 5


def test_invert_runs_the_mirrored_motor_backwards_in_its_own_frame():
    motor, plant, _ = _rig(invert=True)
    motor.run_angle(300, 180, then="hold")
    assert approx(plant.angle_deg, -180, 2)
    assert approx(motor.angle(), 180, 2)


def test_hold_pulls_the_shaft_back_after_a_push():
    motor, plant, _ = _rig()
    motor.run_angle(300, 90, then="hold")
    plant.load_torque_nm = 0.1  # a hand leaning on the wheel
    time.sleep_ms(300)
    plant.load_torque_nm = 0.0
    time.sleep_ms(500)
    assert approx(plant.angle_deg, 90, 2)


def test_wait_false_moves_run_together_and_done_reports_arrival():
    motor, plant, _ = _rig()
    motor.run_angle(400, 400, wait=False)
    assert not motor.done()
    polls = 0
    while not motor.done():
        time.sleep_ms(10)
        polls += 1
    assert polls > 50
    assert approx(plant.angle_deg, 400, 2)


def test_run_target_goes_to_an_absolute_angle_in_the_reset_frame():
    motor, plant, _ = _rig()
    motor.reset_angle(1000)
    motor.run_target(500, 820)
    assert approx(plant.angle_deg, -180, 2)
    assert approx(motor.angle(), 820, 2)


def test_run_until_stalled_stops_at_the_end_stop_under_the_duty_cap():
    motor, plant, rig = _rig()
    rig.wall_deg = 150
    stop_angle = motor.run_until_stalled(200, duty_limit=40)
    assert approx(stop_angle, 150, 1)
    pushing = [duty for _ms, duty in rig.duty_log if duty]
    assert max(abs(d) for d in pushing) <= 40.5
    assert motor._servo.duty_limit == 100
    time.sleep_ms(10)
    assert rig.bridge_duty() is None  # default then="coast"
