"""MG370 closed loop: fine moves on the high-resolution PCNT-counted encoder."""

import time

import _openbricks_native
import machine

from fakes.dc_motor import DCMotorRig, ShaftEdges
from fakes.expect import approx
from openbricks import pins
from openbricks.drivers.mg370 import MG370Motor
from tests.firmware.native.plant import KG_CM_TO_NM, WheelPlant

NEEDS_NATIVE = True
_CPR = 68028


def test_run_angle_lands_within_a_fraction_of_a_degree():
    pins.reset_claims()
    _openbricks_native.motor_process.reset()
    plant = WheelPlant(
        no_load_speed_dps=1000.0,
        stall_torque_nm=3.0 * KG_CM_TO_NM,
        gear_ratio=34.0,
        rotor_inertia_kgm2=6.0e-7,
        wheel_diameter_mm=65.0,
        coulomb_nm=0.004,
        static_nm=0.006,
        counts_per_rev=_CPR,
    )
    motor = MG370Motor(in1=1, in2=2, pwm=17, encoder_a=7, encoder_b=8, pcnt_unit=0)
    DCMotorRig(plant, in1=1, in2=2, pwm=17, counts_per_rev=_CPR, encoder=ShaftEdges(7))
    tick = machine.Timer(0)
    tick.init(freq=1000, callback=lambda _t: _openbricks_native.motor_process.tick(time.ticks_ms()))
    motor.run_angle(300, -270, then="hold")
    time.sleep_ms(300)
    assert approx(plant.angle_deg, -270, 0.1)
    assert approx(motor.angle(), plant.angle_deg, 0.01)
    motor.run_angle(300, 30, then="hold")
    time.sleep_ms(300)
    assert approx(plant.angle_deg, -240, 0.1)
