"""The QTRLineSensor window over the mat: ten analog channels on GPIO 1..10.

Geometry as the manual's standard line-follow window (2.3.1): QTRX-HD-15A
channels 1, 3, 4, 5, 7, 9, 11, 12, 13, 15 at x = -28, -20, -16, -12, -4,
+4, +12, +16, +20, +28 mm across the bar (positive to the robot's right),
wired left to right onto GPIO 1..10. The bar is centred on the chassis
`qtr` site.

Each element is an IR emitter/phototransistor pair: the output voltage rises
as less IR comes back, so a black line reads high and white mat low, as on a
real QTRX. IR reflectance is taken as the strongest linear colour band of
the spot (carbon black absorbs across the spectrum and into the infrared,
while coloured inks pass or reflect infrared much like white), and falls off
with the square of the height above the mount height. Readings are 12-bit
ADC counts with a little seeded noise; one look at the mat serves all ten
channels for a given simulated instant, so a driver reading the pins one by
one still gets one coherent sample.
"""

import math

import mujoco
import numpy as np

from .mat import GroundProbe, footprint_offsets_mm, spot_pattern_m

PINS = (1, 2, 3, 4, 5, 6, 7, 8, 9, 10)
POSITIONS_MM = (-28.0, -20.0, -16.0, -12.0, -4.0, 4.0, 12.0, 16.0, 20.0, 28.0)
_ADC_MAX = 4095


class QTRBarModel:
    def __init__(
        self,
        probe: GroundProbe,
        now_us,
        site: str = "qtr",
        pins=PINS,
        positions_mm=POSITIONS_MM,
        footprint_radius_mm: float = 2.0,
        mount_height_mm: float = 8.0,
        dark_raw: int = 3700,
        raw_per_reflectance: float = 3750.0,
        noise_counts: float = 6.0,
        seed: int = 0,
    ):
        if len(pins) != len(positions_mm):
            raise ValueError(f"QTR model: {len(pins)} pins for {len(positions_mm)} element positions")
        self.probe = probe
        self.now_us = now_us
        self.site_id = mujoco.mj_name2id(probe.model, mujoco.mjtObj.mjOBJ_SITE, site)
        if self.site_id < 0:
            raise ValueError(f"QTR model: the robot has no site {site!r} to mount the bar on")
        self.pins = tuple(pins)
        # Element centres in the sensor frame (x forward, y left): the driver's +x is the robot's right.
        centres = [(0.0, -x) for x in positions_mm]
        self._spots = spot_pattern_m(centres, footprint_offsets_mm(footprint_radius_mm))
        self.mount_height_mm = mount_height_mm
        self.dark_raw = dark_raw
        self.raw_per_reflectance = raw_per_reflectance
        self.noise_counts = noise_counts
        self._seed = seed
        self._rng = None  # made at the first read: most programs never read the bar, nor pay numpy.random
        self._sampled_us = None
        self._raw = [0] * len(self.pins)

    def reflectance(self) -> np.ndarray:
        """IR reflectance 0..1 under each element, left to right, right now."""
        colour, range_mm = self.probe.look(self.site_id, self._spots)
        if math.isinf(range_mm):
            return np.zeros(len(self.pins))
        falloff = min(1.5, (self.mount_height_mm / range_mm) ** 2)
        return colour.max(axis=1) * falloff

    def raw12(self) -> list[int]:
        """Every element's 12-bit ADC count, sampled once per simulated instant."""
        now = self.now_us()
        if now != self._sampled_us:
            self._sampled_us = now
            counts = self.dark_raw - self.raw_per_reflectance * self.reflectance()
            if self._rng is None:
                self._rng = np.random.default_rng(self._seed)
            counts += self._rng.normal(0.0, self.noise_counts, len(counts))
            self._raw = np.clip(counts, 0, _ADC_MAX).astype(int).tolist()
        return self._raw

    def channel(self, pin: int) -> "AnalogChannel":
        """The ADC input wired to `pin`."""
        if pin not in self.pins:
            raise ValueError(f"the QTR bar is wired to GPIO {self.pins}, not GPIO {pin}")
        return AnalogChannel(self, self.pins.index(pin))


class AnalogChannel:
    """One ADC input: `read()` is the 12-bit count, `read_u16()` the same scaled to 16 bits the way
    the ESP32 port does it."""

    def __init__(self, bar: QTRBarModel, index: int):
        self.bar = bar
        self.index = index

    def read(self) -> int:
        return self.bar.raw12()[self.index]

    def read_u16(self) -> int:
        raw = self.read()
        return (raw << 4) | (raw >> 8)
