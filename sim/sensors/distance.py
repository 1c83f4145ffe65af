"""Range finders on the chassis `distance` site: VL53L0X and VL53L1X (I2C) and an HC-SR04 (echo pulse).

Every range comes from MuJoCo ray casts forward from the site along its +x
axis (the robot's forward direction), skipping the robot's own geoms. A laser
ToF sensor reports the target on its optical axis (one ray); an ultrasonic
ping returns from the nearest thing in its ~15 degree cone (a fan of rays,
nearest hit wins), which is why a sonar sees a post that a laser slips past.
Ranges carry small seeded Gaussian noise and are measured when the chip's
ranging completes, i.e. the first time the driver reads a result after the
chip's measurement time.

VL53L0X (8-bit registers, model ID 0xEE at 0xC0): SYSRANGE_START 0x00 = 1
starts one ranging; RESULT_INTERRUPT_STATUS 0x13 bit 0 flags a new sample
until SYSTEM_INTERRUPT_CLEAR 0x0B; the range is big-endian at 0x1E; nothing
in range reads 8190.
VL53L1X (16-bit registers, model ID 0xEACC at 0x010F): firmware booted flag
0x00E5 bit 0; SYSTEM_MODE_START 0x0087 = 0x40 starts a ranging;
GPIO_TIO_HV_STATUS 0x0031 bit 0 is 1 until data is ready (active low);
SYSTEM_INTERRUPT_CLEAR 0x0086 re-arms it; RESULT_RANGE_STATUS 0x0089 reads 9
for a valid range and 4 (signal fail) for nothing in range; the range is
big-endian at 0x0096.
"""

import math
import random

import mujoco
import numpy as np

from ..chassis import ROBOT_BODY
from .registers import RegisterDevice

SOUND_MM_PER_US = 0.343


class ForwardRay:
    """Distance (mm) from the `distance` site to the first surface ahead, or inf.

    `cone_deg` > 0 casts a horizontal fan of `rays` across that cone and reports the nearest hit.
    """

    def __init__(self, model: mujoco.MjModel, data: mujoco.MjData, site="distance", cone_deg=0.0, rays=1):
        self.model = model
        self.data = data
        self.site_id = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_SITE, site)
        if self.site_id < 0:
            raise ValueError(f"range finder model: the robot has no site {site!r} to mount it on")
        self.robot_body = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, ROBOT_BODY)
        half = math.radians(cone_deg) / 2
        angles = np.linspace(-half, half, rays) if rays > 1 else np.zeros(1)
        # Directions in the site frame: forward (+x), swept about the site's z axis.
        self._local_dirs = np.stack([np.cos(angles), np.sin(angles), np.zeros_like(angles)], axis=1)
        self._geom = np.zeros(len(angles), dtype=np.int32)
        self._dist = np.zeros(len(angles))

    def range_mm(self) -> float:
        xmat = self.data.site_xmat[self.site_id].reshape(3, 3)
        vec = (self._local_dirs @ xmat.T).ravel()
        mujoco.mj_multiRay(
            self.model,
            self.data,
            self.data.site_xpos[self.site_id],
            vec,
            None,
            1,
            self.robot_body,
            self._geom,
            self._dist,
            None,
            len(self._geom),
            100.0,
        )
        hits = self._dist[self._dist >= 0]
        return float(hits.min()) * 1000.0 if len(hits) else math.inf


class _Ranging:
    """The measurement side both ToF chips share: a ranging started at a time completes after
    `ranging_ms`, measured at its first read after that, within [min_mm, max_mm] or no target."""

    def __init__(self, ray: ForwardRay, now_us, ranging_ms, min_mm, max_mm, noise_mm, seed):
        self.ray = ray
        self.now_us = now_us
        self.ranging_us = int(ranging_ms * 1000)
        self.min_mm = min_mm
        self.max_mm = max_mm
        self.noise_mm = noise_mm
        self._rng = random.Random(seed)
        self.started_us = None
        self.result_mm = None  # None: no ranging completed; inf: nothing in range
        self.ready = False
        self.rangings = 0

    def start(self):
        self.started_us = self.now_us()
        self.rangings += 1

    def update(self):
        if self.started_us is not None and self.now_us() - self.started_us >= self.ranging_us:
            self.started_us = None
            distance = self.ray.range_mm()
            if distance > self.max_mm:
                self.result_mm = math.inf
            else:
                noisy = distance + self._rng.gauss(0.0, self.noise_mm)
                self.result_mm = max(self.min_mm, noisy)
            self.ready = True


class VL53L0XModel(RegisterDevice):
    SYSRANGE_START, INTERRUPT_CLEAR, INTERRUPT_STATUS, RANGE_MM, MODEL_ID = 0x00, 0x0B, 0x13, 0x1E, 0xC0
    NO_TARGET_MM = 8190

    def __init__(self, ray: ForwardRay, now_us, max_mm=2000.0, noise_mm=0.5, ranging_ms=33, seed=0):
        super().__init__()
        self.ranging = _Ranging(ray, now_us, ranging_ms, 20.0, max_mm, noise_mm, seed)
        self.regs = bytearray(256)
        self.regs[self.MODEL_ID] = 0xEE
        self.regs[0xC1] = 0xAA  # module type
        self.regs[0xC2] = 0x10  # revision

    def write_register(self, reg, value):
        self.regs[reg] = value
        if reg == self.SYSRANGE_START and value & 0x01:
            self.ranging.start()
        elif reg == self.INTERRUPT_CLEAR and value & 0x01:
            self.ranging.ready = False

    def read_register(self, reg):
        r = self.ranging
        r.update()
        if reg == self.INTERRUPT_STATUS:
            return 0x01 if r.ready else 0x00
        if reg in (self.RANGE_MM, self.RANGE_MM + 1):
            mm = self.NO_TARGET_MM if r.result_mm is None or math.isinf(r.result_mm) else round(r.result_mm)
            return mm >> 8 if reg == self.RANGE_MM else mm & 0xFF
        if reg == self.SYSRANGE_START:
            return 0x01 if r.started_us is not None else 0x00
        return self.regs[reg]


class VL53L1XModel(RegisterDevice):
    ADDRESS_BYTES = 2
    INTERRUPT_CLEAR, MODE_START, TIO_HV_STATUS, RANGE_STATUS, RANGE_MM = (
        0x0086,
        0x0087,
        0x0031,
        0x0089,
        0x0096,
    )
    FIRMWARE_STATUS, MODEL_ID = 0x00E5, 0x010F
    RANGE_VALID, SIGNAL_FAIL = 9, 4

    def __init__(
        self,
        ray: ForwardRay,
        now_us,
        model_id=0xEACC,
        max_mm=4000.0,
        noise_mm=0.5,
        ranging_ms=50,
        boot_ms=2,
        seed=0,
    ):
        super().__init__()
        self.ranging = _Ranging(ray, now_us, ranging_ms, 40.0, max_mm, noise_mm, seed)
        self.now_us = now_us
        self.booted_us = now_us() + int(boot_ms * 1000)
        self.regs = {self.MODEL_ID: model_id >> 8, self.MODEL_ID + 1: model_id & 0xFF}

    def write_register(self, reg, value):
        self.regs[reg] = value
        if reg == self.MODE_START and value == 0x40:
            self.ranging.start()
        elif reg == self.INTERRUPT_CLEAR and value & 0x01:
            self.ranging.ready = False

    def read_register(self, reg):
        r = self.ranging
        r.update()
        if reg == self.FIRMWARE_STATUS:
            return 0x01 if self.now_us() >= self.booted_us else 0x00
        if reg == self.TIO_HV_STATUS:
            return 0x00 if r.ready else 0x01
        in_range = r.result_mm is not None and not math.isinf(r.result_mm)
        if reg == self.RANGE_STATUS:
            return self.RANGE_VALID if in_range else self.SIGNAL_FAIL
        if reg in (self.RANGE_MM, self.RANGE_MM + 1):
            mm = round(r.result_mm) if in_range else 0
            return mm >> 8 if reg == self.RANGE_MM else mm & 0xFF
        return self.regs.get(reg, 0)


class HCSR04Model:
    """An ultrasonic ranger: a pulse on TRIG fires a ping; ECHO then stays high for the round trip.

    `echo_pulse_us(level)` is what machine.time_pulse_us(echo, level) measures: the width of the
    echo that follows the last trigger, or -1 when there was no trigger since the last echo or
    nothing lies within `max_mm` (the caller's timeout applies on top). `trigger()` is called on
    each falling edge of TRIG.
    """

    def __init__(self, ray: ForwardRay, max_mm=4000.0, min_mm=20.0, noise_mm=1.0, seed=0):
        self.ray = ray
        self.max_mm = max_mm
        self.min_mm = min_mm
        self.noise_mm = noise_mm
        self._rng = random.Random(seed)
        self._armed = False
        self._trig_level = 0
        self.pings = 0

    def trig_driven(self, _pin, level) -> None:
        """The program drove TRIG: a high-to-low transition ends the trigger pulse and fires a ping."""
        if self._trig_level and not level:
            self.trigger()
        self._trig_level = 1 if level else 0

    def trigger(self) -> None:
        self._armed = True
        self.pings += 1

    def echo_pulse_us(self, level: int = 1) -> int:
        if not level or not self._armed:
            return -1
        self._armed = False
        distance = self.ray.range_mm()
        if distance > self.max_mm:
            return -1
        distance = max(self.min_mm, distance + self._rng.gauss(0.0, self.noise_mm))
        return int(round(2.0 * distance / SOUND_MM_PER_US))


def sonar_ray(model, data, site="distance") -> ForwardRay:
    """The HC-SR04's beam: a 15 degree fan of seven rays."""
    return ForwardRay(model, data, site, cone_deg=15.0, rays=7)
