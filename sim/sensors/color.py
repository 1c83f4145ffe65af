"""AMS TCS34725 colour sensor over the mat: RGBC counts from the surface under a `color_N` site.

Register map and command byte as the datasheet gives them (and as
openbricks.drivers.tcs34725 drives them): the first byte of a transaction is
a command (bit 7 set; TYPE in bits 6:5, 01 = auto-increment), ENABLE 0x00
(PON, AEN), ATIME 0x01 (256 - cycles of 2.4 ms), CONTROL 0x0F (gain 1, 4,
16, 60), ID 0x12 = 0x44, STATUS 0x13 (AVALID once an integration has
completed), clear/red/green/blue data little-endian from 0x14.

The light model: the board's white LED lights a small spot of the surface;
each colour channel collects `white_counts_per_cycle` counts per 2.4 ms cycle
at gain 1 from a perfect white reflector at the mount height, times the
spot's linear reflectance in that band, falling off with the square of the
distance above that height. The clear diode sees the sum of the three bands.
A little room light and seeded multiplicative noise keep the numbers honest.
The defaults put white mat at about 85 % of full scale at the driver's
default 2.4 ms / 16x, and black line below 5 %.
"""

import math
import random

import mujoco
import numpy as np

from .mat import GroundProbe, footprint_offsets_mm, spot_pattern_m
from .registers import EIO, RegisterDevice

ADDRESS = 0x29
_CYCLE_US = 2400
_GAINS = (1, 4, 16, 60)
_MAX_FALLOFF = 1.5  # closer than the mount height brightens the spot, but the optics saturate


class TCS34725Model(RegisterDevice):
    ENABLE, ATIME, CONTROL, ID, STATUS, CDATAL = 0x00, 0x01, 0x0F, 0x12, 0x13, 0x14

    def __init__(
        self,
        probe: GroundProbe,
        site: str,
        now_us,
        chip_id: int = 0x44,
        footprint_radius_mm: float = 3.0,
        mount_height_mm: float = 8.0,
        white_counts_per_cycle: float = 18.9,
        room_counts_per_cycle: float = 0.3,
        noise_pct: float = 0.4,
        seed: int = 0,
    ):
        super().__init__()
        self.probe = probe
        self.site_id = mujoco.mj_name2id(probe.model, mujoco.mjtObj.mjOBJ_SITE, site)
        if self.site_id < 0:
            raise ValueError(f"TCS34725 model: the robot has no site {site!r} to mount the sensor on")
        self.now_us = now_us
        self._spots = spot_pattern_m([(0.0, 0.0)], footprint_offsets_mm(footprint_radius_mm))
        self.mount_height_mm = mount_height_mm
        self.white_counts_per_cycle = white_counts_per_cycle
        self.room_counts_per_cycle = room_counts_per_cycle
        self.noise = noise_pct / 100.0
        self._rng = random.Random(seed)
        self.regs = bytearray(32)
        self.regs[self.ATIME] = 0xFF
        self.regs[self.ID] = chip_id
        self._auto_increment = False
        self._pon_us = None
        self._aen_us = None
        self._latched_cycle = None
        self._counts = (0, 0, 0, 0)

    # -- the command byte -------------------------------------------------------------------------

    def select(self, address_bytes: bytes) -> int:
        command = address_bytes[0]
        if not command & 0x80:
            raise OSError(EIO, "TCS34725: the first byte of a transaction must be a command (bit 7 set)")
        self._auto_increment = (command & 0x60) == 0x20
        return command & 0x1F

    def next_register(self, reg: int) -> int:
        return (reg + 1) & 0x1F if self._auto_increment else reg

    # -- registers --------------------------------------------------------------------------------

    def write_register(self, reg: int, value: int) -> None:
        self.regs[reg] = value
        if reg == self.ENABLE:
            now = self.now_us()
            if value & 0x01:
                if self._pon_us is None:
                    self._pon_us = now
            else:
                self._pon_us = None
            self._aen_us = now if (value & 0x03) == 0x03 else None
            self._latched_cycle = None
            self._counts = (0, 0, 0, 0)

    def read_register(self, reg: int) -> int:
        if reg == self.STATUS:
            return 0x01 if self._completed_integrations() > 0 else 0x00
        if self.CDATAL <= reg < self.CDATAL + 8:
            counts = self._latched_counts()
            index, high = divmod(reg - self.CDATAL, 2)
            return (counts[index] >> 8) if high else counts[index] & 0xFF
        return self.regs[reg]

    # -- integration --------------------------------------------------------------------------------

    def cycles(self) -> int:
        return 256 - self.regs[self.ATIME]

    def gain(self) -> int:
        return _GAINS[self.regs[self.CONTROL] & 0x03]

    def _completed_integrations(self) -> int:
        if self._aen_us is None or self._pon_us is None:
            return 0
        # Integration starts with AEN but not before the oscillator's 2.4 ms warm-up after PON.
        start = max(self._aen_us, self._pon_us + _CYCLE_US)
        elapsed = self.now_us() - start
        return max(0, elapsed // (_CYCLE_US * self.cycles()))

    def _latched_counts(self):
        """The data registers hold the last completed integration; it is measured when first read."""
        done = self._completed_integrations()
        if done == 0:
            return (0, 0, 0, 0)
        if done != self._latched_cycle:
            self._latched_cycle = done
            self._counts = self.measure()
        return self._counts

    def light_per_cycle(self) -> np.ndarray:
        """(red, green, blue) counts one 2.4 ms cycle at gain 1 collects from the surface right now."""
        reflectance, range_mm = self.probe.look(self.site_id, self._spots)
        falloff = 0.0 if math.isinf(range_mm) else min(_MAX_FALLOFF, (self.mount_height_mm / range_mm) ** 2)
        return reflectance[0] * self.white_counts_per_cycle * falloff + self.room_counts_per_cycle

    def measure(self):
        """(clear, red, green, blue) as the ADCs report them after the configured integration."""
        rgb = self.light_per_cycle() * self.cycles() * self.gain()
        rgb = [v * (1.0 + self._rng.gauss(0.0, self.noise)) for v in rgb]
        full_scale = min(65535, 1024 * self.cycles())
        red, green, blue = (min(full_scale, max(0, int(v))) for v in rgb)
        clear = min(full_scale, max(0, int(sum(rgb))))
        return (clear, red, green, blue)
