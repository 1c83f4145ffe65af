"""Robots for the DriveBase tests, built on the fake board: motors, plants, chassis and (optionally) a gyro.

Every builder starts from a clean slate (pins, servo buses, the native scheduler and the test bus
engine), because the tests are plain functions run back to back in one process.
"""

import _openbricks_native
import machine

from fakes.chassis import Chassis
from fakes.dc_motor import DCMotorRig, QuadratureLines
from fakes.scs_servo import FakeServo, ScsBus
from fakes.spi_imu import ICM45686Chip
from openbricks import pins
from openbricks.drivers import st3215
from tests.firmware.native.plant import KG_CM_TO_NM, WheelPlant

WHEEL_MM = 65.0
TRACK_MM = 150.0
SERVO_WHEEL_MM = 56.0
SERVO_TRACK_MM = 114.0
IMU_PINS = {"sck": 4, "mosi": 5, "miso": 6, "cs": 15}


def clean_slate():
    pins.reset_claims()
    st3215.forget_buses()
    _openbricks_native.motor_process.reset()


def jgb37_plant():
    """A 12 V JGB37-520 1:30 driving a 65 mm wheel, carrying half of a 1 kg robot."""
    return WheelPlant(
        no_load_speed_dps=1230.0,
        stall_torque_nm=2.5 * KG_CM_TO_NM,
        gear_ratio=30.0,
        rotor_inertia_kgm2=6.0e-7,
        wheel_diameter_mm=WHEEL_MM,
        coulomb_nm=0.004,
        static_nm=0.006,
        counts_per_rev=1320,
    )


def gyro_chip():
    chip = ICM45686Chip()
    machine.board.attach_spi(IMU_PINS["cs"], chip)
    return chip


def icm45686():
    from openbricks.drivers.icm45686 import ICM45686

    imu = ICM45686(sample_hz=1000, **IMU_PINS)
    imu._yaw.seed_bias(0.0)  # as after save_calibration(): no half-second stillness wait
    return imu


class EncoderRobot:
    """Two JGB37-520s on an L298N (manual 2.7 wiring), the right one mounted mirror-image."""

    def __init__(self, gyro=False, slip=(0.0, 0.0)):
        from openbricks.drivers.jgb37_520 import JGB37Motor

        clean_slate()
        self.plants = (jgb37_plant(), jgb37_plant())
        self.rigs = (
            DCMotorRig(self.plants[0], 1, 2, 17, 1320, QuadratureLines(7, 8)),
            DCMotorRig(self.plants[1], 9, 10, 11, 1320, QuadratureLines(12, 13)),
        )
        self.left = JGB37Motor(in1=1, in2=2, pwm=17, encoder_a=7, encoder_b=8)
        self.right = JGB37Motor(in1=9, in2=10, pwm=11, encoder_a=12, encoder_b=13, invert=True)
        self.chip = gyro_chip() if gyro else None
        self.imu = icm45686() if gyro else None
        left, right = self.plants
        self.chassis = Chassis(
            lambda: left.angle_deg,
            lambda: -right.angle_deg,
            WHEEL_MM,
            TRACK_MM,
            gyro=self.chip,
            slip=slip,
        )

    def drivebase(self):
        from openbricks.robotics import DriveBase

        return DriveBase(
            self.left, self.right, wheel_diameter_mm=WHEEL_MM, axle_track_mm=TRACK_MM, imu=self.imu
        )

    def close(self):
        """Take this robot off the board (its plants, chassis and IMU stop running on the clock)."""
        for rig in self.rigs:
            rig.close()
        self.chassis.close()
        if self.imu is not None:
            self.imu.close()
        for motor in (self.left, self.right):
            motor.close()

    def wheel_speeds_dps(self):
        """Forward-positive wheel speeds as the plants turn them."""
        return self.plants[0].speed_dps, -self.plants[1].speed_dps

    def bridge_duties(self):
        return self.rigs[0].bridge_duty(), self.rigs[1].bridge_duty()


class ServoRobot:
    """Two ST-3032s on UART1 (TX 14, RX 41), ids 1 (left) and 2 (right, mounted mirror-image)."""

    def __init__(self, extra_ids=(), silent_ids=()):
        from openbricks.drivers.st3032 import ST3032Motor

        clean_slate()
        self.bus = ScsBus()
        for servo_id in (1, 2) + tuple(extra_ids):
            self.bus.add(FakeServo(servo_id))
        machine.board.attach_uart(1, self.bus)
        self.left = ST3032Motor(servo_id=1)
        self.right = ST3032Motor(servo_id=2, invert=True)
        self.extras = [ST3032Motor(servo_id=i) for i in extra_ids]
        for servo_id in silent_ids:
            self.bus.servo(servo_id).silent = True
        self.servos = (self.bus.servo(1), self.bus.servo(2))
        left, right = self.servos
        self.chassis = Chassis(left.angle_deg, lambda: -right.angle_deg(), SERVO_WHEEL_MM, SERVO_TRACK_MM)

    def drivebase(self):
        from openbricks.robotics import DriveBase

        return DriveBase(
            self.left, self.right, wheel_diameter_mm=SERVO_WHEEL_MM, axle_track_mm=SERVO_TRACK_MM
        )

    def engine(self):
        """The bus engine the DriveBase handed UART1 to (`_openbricks_native.serial_bus(1)`)."""
        from openbricks.robotics import wheels

        return wheels._ports[1].engine
