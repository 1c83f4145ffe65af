"""IMUs on the chassis body: an ICM-45686 on SPI and a BNO055 on I2C.

`BodyMotion` reads what an IMU fixed to the robot body feels, straight from
the free joint: angular rate in the body frame (MuJoCo keeps a free joint's
rotational velocity in local coordinates), specific force (acceleration
minus gravity, rotated into the body frame: +1 g up at rest), and attitude.
Both chips are mounted face up at the `imu` site, so their z axis is the
body's and their right-handed gyro z reads counter-clockwise turns as
positive; the drivers turn that into the clockwise-positive heading.

ICM-45686 (SPI, datasheet DS-000577): the first byte is the register, bit 7
set for a read, and the chip answers from consecutive registers. Modelled:
sensor data 0x00-0x0B (accel x, y, z then gyro x, y, z, little-endian int16;
-32768 while that sensor is off), PWR_MGMT0 0x10 (gyro/accel modes),
ACCEL_CONFIG0 0x1B / GYRO_CONFIG0 0x1C (full scale in bits 6:4), WHO_AM_I
0x72 = 0xE9, REG_MISC2 0x7F bit 1 soft reset (registers unusable for 1 ms).
The gyro carries a seeded constant bias (the one the driver learns at rest)
and white noise. Its rates are the body's average rate since the previous
read, as the chip's output filter delivers them: the samples integrate to the
rotation the body really made, however the read rate beats against the
motion (an instantaneous rate aliases when the gyro closes a heading loop).

BNO055 (I2C, page 0): CHIP_ID 0xA0, OPR_MODE 0x3D (CONFIG 0x00; the fusion
outputs read zero until a fusion mode has run 7 ms), Euler heading / roll /
pitch at 0x1A (1/16 degree, heading 0..360 clockwise from where fusion
started), gyro at 0x14 (1/16 dps), acceleration at 0x08 (1/100 m/s^2). The
chip's own fusion is modelled as the true heading plus seeded noise and an
optional slow drift.
"""

import math
import random
import struct

import mujoco
import numpy as np

from ..chassis import ROBOT_BODY
from .registers import RegisterDevice

GRAVITY_MS2 = 9.80665


class BodyMotion:
    """What an IMU rigidly fixed to the robot body senses, read from the body's free joint."""

    def __init__(self, model: mujoco.MjModel, data: mujoco.MjData):
        self.model = model
        self.data = data
        body = model.body(ROBOT_BODY)
        joint = int(body.jntadr[0])
        if joint < 0 or model.jnt_type[joint] != mujoco.mjtJoint.mjJNT_FREE:
            raise ValueError("IMU model: the robot body has no free joint to read motion from")
        self._qpos = int(model.jnt_qposadr[joint])
        self._dof = int(model.jnt_dofadr[joint])
        self._gravity = np.array(model.opt.gravity)

    def quat(self) -> np.ndarray:
        return self.data.qpos[self._qpos + 3 : self._qpos + 7]

    def rates_dps(self) -> np.ndarray:
        """(x, y, z) body-frame angular rate, right-handed (z positive counter-clockwise from above)."""
        return np.degrees(self.data.qvel[self._dof + 3 : self._dof + 6])

    def rotation_since_deg(self, earlier_quat: np.ndarray) -> np.ndarray:
        """The body-frame rotation vector (degrees) from attitude `earlier_quat` to now."""
        rotation = np.zeros(3)
        mujoco.mju_subQuat(rotation, self.quat(), earlier_quat)
        return np.degrees(rotation)

    def specific_force_ms2(self) -> np.ndarray:
        """What an accelerometer reads, in the body frame: acceleration minus gravity."""
        accel_world = self.data.qacc[self._dof : self._dof + 3] - self._gravity
        rot = np.zeros(9)
        mujoco.mju_quat2Mat(rot, self.quat())
        return rot.reshape(3, 3).T @ accel_world

    def yaw_roll_pitch_deg(self) -> tuple[float, float, float]:
        """Counter-clockwise yaw, roll about +x, pitch about +y (ZYX Euler angles), degrees."""
        w, x, y, z = self.quat()
        yaw = math.atan2(2 * (w * z + x * y), 1 - 2 * (y * y + z * z))
        roll = math.atan2(2 * (w * x + y * z), 1 - 2 * (x * x + y * y))
        pitch = math.asin(max(-1.0, min(1.0, 2 * (w * y - z * x))))
        return math.degrees(yaw), math.degrees(roll), math.degrees(pitch)


def _counts(value, full_scale):
    return max(-32767, min(32767, int(round(value * 32768.0 / full_scale))))


class ICM45686Model:
    ACCEL_DATA, PWR_MGMT0, ACCEL_CONFIG0, GYRO_CONFIG0, WHO_AM_I, MISC2 = 0x00, 0x10, 0x1B, 0x1C, 0x72, 0x7F
    GYRO_FS_DPS = (4000.0, 2000.0, 1000.0, 500.0, 250.0, 125.0, 62.5, 31.25, 15.625)
    ACCEL_FS_G = (32.0, 16.0, 8.0, 4.0, 2.0)
    NO_DATA = -32768
    MIN_SAMPLE_US = 500  # the output data rate's period at the driver's fastest setting (2 kHz)

    def __init__(self, motion: BodyMotion, now_us, bias_dps=None, noise_dps=0.03, seed=0):
        """`bias_dps` is the gyro's zero-rate offset (x, y, z); None draws a small one from the seed
        (up to 0.5 dps, a typical part at room temperature)."""
        self.motion = motion
        self.now_us = now_us
        self._rng = random.Random(seed)
        if bias_dps is None:
            bias_dps = tuple(self._rng.uniform(-0.5, 0.5) for _ in range(3))
        self.bias_dps = np.array(bias_dps, dtype=float)
        self.noise_dps = noise_dps
        self.soft_resets = 0
        self._reset()
        self._usable_from_us = 0  # powered up long before the program starts
        self._filtered_since = None  # (time us, attitude) the next averaged rate starts from
        self._filtered_dps = np.zeros(3)

    def _filtered_rates_dps(self) -> np.ndarray:
        """The average body rate since the previous read (reads closer than a sample period apart,
        such as accel and gyro in two transfers, see the same output)."""
        now = self.now_us()
        quat = self.motion.quat().copy()
        if self._filtered_since is None:
            self._filtered_dps = self.motion.rates_dps()
        else:
            then, earlier = self._filtered_since
            if now - then < self.MIN_SAMPLE_US:
                return self._filtered_dps
            self._filtered_dps = self.motion.rotation_since_deg(earlier) / ((now - then) * 1e-6)
        self._filtered_since = (now, quat)
        return self._filtered_dps

    def _reset(self):
        self.regs = bytearray(128)
        self.regs[self.ACCEL_CONFIG0] = 0x06  # +-32 g after reset
        self.regs[self.GYRO_CONFIG0] = 0x06  # +-4000 dps
        self.regs[self.WHO_AM_I] = 0xE9
        self._usable_from_us = self.now_us() + 1000

    def gyro_fs_dps(self):
        return self.GYRO_FS_DPS[min(self.regs[self.GYRO_CONFIG0] >> 4 & 0x0F, 8)]

    def accel_fs_g(self):
        return self.ACCEL_FS_G[min(self.regs[self.ACCEL_CONFIG0] >> 4 & 0x07, 4)]

    def sample(self) -> bytes:
        """The 12 data bytes as the chip would latch them now."""
        pwr = self.regs[self.PWR_MGMT0]
        accel_on = (pwr & 0x03) in (2, 3)
        gyro_on = (pwr >> 2 & 0x03) in (2, 3)
        if accel_on:
            accel = [_counts(a / GRAVITY_MS2, self.accel_fs_g()) for a in self.motion.specific_force_ms2()]
        else:
            accel = [self.NO_DATA] * 3
        if gyro_on:
            rates = self._filtered_rates_dps() + self.bias_dps
            noisy = [r + self._rng.gauss(0.0, self.noise_dps) for r in rates]
            gyro = [_counts(r, self.gyro_fs_dps()) for r in noisy]
        else:
            gyro = [self.NO_DATA] * 3
        return struct.pack("<6h", *accel, *gyro)

    def transfer(self, data: bytes) -> bytes:
        """One chip-select window: the bytes clocked in, and the bytes clocked out meanwhile."""
        if self.now_us() < self._usable_from_us:
            return bytes(len(data))
        reg = data[0] & 0x7F
        if data[0] & 0x80:
            block = self.sample() if reg < 12 else b""
            out = bytearray(len(data))
            for i in range(1, len(data)):
                r = (reg + i - 1) & 0x7F
                out[i] = block[r] if r < len(block) else self.regs[r]
            return bytes(out)
        for i, value in enumerate(data[1:]):
            r = (reg + i) & 0x7F
            if r == self.MISC2 and value & 0x02:
                self.soft_resets += 1
                self._reset()
            elif r != self.WHO_AM_I:
                self.regs[r] = value
        return bytes(len(data))


class BNO055Model(RegisterDevice):
    CHIP_ID, PAGE_ID, ACC_DATA, GYR_DATA, EUL_DATA = 0x00, 0x07, 0x08, 0x14, 0x1A
    UNIT_SEL, OPR_MODE, PWR_MODE, SYS_TRIGGER = 0x3B, 0x3D, 0x3E, 0x3F
    CONFIG_MODE = 0x00
    FUSION_START_MS = 7

    def __init__(self, motion: BodyMotion, now_us, heading_noise_deg=0.05, drift_dps=0.0, seed=0):
        super().__init__()
        self.motion = motion
        self.now_us = now_us
        self.heading_noise_deg = heading_noise_deg
        self.drift_dps = drift_dps
        self._rng = random.Random(seed)
        self.regs = bytearray(128)
        self.regs[self.CHIP_ID] = 0xA0
        self.regs[0x01] = 0xFB  # accelerometer ID
        self.regs[0x02] = 0x32  # magnetometer ID
        self.regs[0x03] = 0x0F  # gyro ID
        self.regs[self.UNIT_SEL] = 0x80
        self._mode_since_us = now_us()
        self._fusion_yaw_deg = None
        self._fusion_us = None
        self._sample_us = None
        self._sample = bytes(18)

    def write_register(self, reg, value):
        if reg == self.SYS_TRIGGER and value & 0x20:  # RST_SYS: back to power-on defaults
            self.__init__(self.motion, self.now_us, self.heading_noise_deg, self.drift_dps)
            return
        self.regs[reg] = value
        if reg == self.OPR_MODE:
            self._mode_since_us = self.now_us()
            if value & 0x0F != self.CONFIG_MODE:
                # Relative-heading fusion: zero where the robot points when fusion starts.
                self._fusion_yaw_deg = self.motion.yaw_roll_pitch_deg()[0]
                self._fusion_us = self._mode_since_us

    def fusing(self) -> bool:
        return (
            self.regs[self.OPR_MODE] & 0x0F != self.CONFIG_MODE
            and self.now_us() - self._mode_since_us >= self.FUSION_START_MS * 1000
        )

    def _outputs(self) -> bytes:
        """Acceleration, gyro and Euler blocks (0x08..0x1F) from one coherent sample per instant."""
        now = self.now_us()
        if now != self._sample_us:
            self._sample_us = now
            yaw, roll, pitch = self.motion.yaw_roll_pitch_deg()
            drift = self.drift_dps * (now - self._fusion_us) / 1e6
            heading = (
                self._fusion_yaw_deg - yaw + drift + self._rng.gauss(0.0, self.heading_noise_deg)
            ) % 360
            accel = self.motion.specific_force_ms2() * 100
            gyro = self.motion.rates_dps() * 16
            self._sample = struct.pack(
                "<3h3h3h",
                *(int(round(v)) for v in accel),
                *(int(round(v)) for v in gyro),
                *(int(round(v * 16)) for v in (heading, roll, pitch)),
            )
        return self._sample

    def read_register(self, reg):
        if self.ACC_DATA <= reg < self.EUL_DATA + 6:
            if not self.fusing():
                return 0
            offset = reg - self.ACC_DATA
            if reg >= self.EUL_DATA:
                offset = 12 + (reg - self.EUL_DATA)
            elif reg >= self.GYR_DATA:
                offset = 6 + (reg - self.GYR_DATA)
            elif reg >= self.ACC_DATA + 6:  # magnetometer block 0x0E-0x13: unused in IMU mode
                return 0
            return self._sample_byte(offset)
        return self.regs[reg]

    def _sample_byte(self, offset):
        return self._outputs()[offset]
