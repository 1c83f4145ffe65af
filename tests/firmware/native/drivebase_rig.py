"""A rigid two-wheel chassis on two WheelPlants, closed around a drivebase controller at 1 kHz.

The controller sees only what a hub sees: each wheel's quantised encoder angle (and, with a gyro, the
body heading) going in, a duty or a release per wheel coming out. The rig integrates the chassis pose
from the wheels' ground travel, so the figures the tests assert (distance, heading, lateral drift,
radius) are measured on the "real" robot, not read back from the controller's own estimate.

Frames: x forward at the start, y to the left; heading in degrees, clockwise from above positive (the
drivebase's convention), so a right turn makes y negative.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field

from tests.firmware.native.plant import WheelPlant

WHEEL_DIAMETER_MM = 56.0
AXLE_TRACK_MM = 114.0
PERIOD_MS = 1
NO_LOAD_SPEED_DPS = 888.0  # WheelPlant's default motor (an ST-3032)
MM_PER_WHEEL_DEG = math.pi * WHEEL_DIAMETER_MM / 360.0


class Chassis:
    """Two wheel plants joined by a rigid axle; pose from their ground travel (no sideways slip).

    ``effectiveness`` scales a wheel's whole duty-to-output line: at a given duty it delivers that
    fraction of its twin's torque at rest *and* of its twin's speed at no load, as a weaker motor or a
    sagging supply on one side does. That is the manual's "one wheel at 0.9x commanded speed"; scaling
    torque alone (WheelPlant's own ``effectiveness``) leaves the no-load speed equal, and the two wheels
    would differ only while accelerating.

    ``slip`` is the fraction of a wheel's rotation that does not become ground travel (a spinning tyre):
    its encoder sees the full rotation, the chassis only the rest.
    """

    def __init__(
        self,
        *,
        wheel_diameter_mm: float = WHEEL_DIAMETER_MM,
        axle_track_mm: float = AXLE_TRACK_MM,
        effectiveness: tuple[float, float] = (1.0, 1.0),
        slip: tuple[float, float] = (0.0, 0.0),
    ) -> None:
        self.wheel_diameter_mm = wheel_diameter_mm
        self.axle_track_mm = axle_track_mm
        self.wheels = tuple(
            WheelPlant(
                wheel_diameter_mm=wheel_diameter_mm,
                effectiveness=e,
                no_load_speed_dps=e * NO_LOAD_SPEED_DPS,
            )
            for e in effectiveness
        )
        self.slip = slip
        self.x_mm = 0.0
        self.y_mm = 0.0
        self.heading_deg = 0.0
        self.travel_mm = 0.0

    @property
    def encoders_deg(self) -> tuple[float, float]:
        return self.wheels[0].encoder_deg, self.wheels[1].encoder_deg

    @property
    def speeds_dps(self) -> tuple[float, float]:
        return self.wheels[0].speed_dps, self.wheels[1].speed_dps

    def step(self, duties: tuple[float | None, float | None], dt_s: float) -> None:
        before = [w.angle_deg for w in self.wheels]
        for wheel, duty in zip(self.wheels, duties, strict=True):
            wheel.step(duty, dt_s)
        mm_per_deg = math.pi * self.wheel_diameter_mm / 360.0
        ground = [
            (w.angle_deg - a0) * mm_per_deg * (1.0 - s)
            for w, a0, s in zip(self.wheels, before, self.slip, strict=True)
        ]
        forward = 0.5 * (ground[0] + ground[1])
        turn_rad = (ground[0] - ground[1]) / self.axle_track_mm
        mid = -math.radians(self.heading_deg) - 0.5 * turn_rad
        self.x_mm += forward * math.cos(mid)
        self.y_mm += forward * math.sin(mid)
        self.heading_deg += math.degrees(turn_rad)
        self.travel_mm += forward


@dataclass
class Sample:
    t_ms: int
    duties: tuple[float | None, float | None]
    x_mm: float
    y_mm: float
    heading_deg: float
    speeds_dps: tuple[float, float]


@dataclass
class Rig:
    """Runs a controller against a Chassis, one 1 ms period at a time, and records a trace.

    ``controller(now_ms, left_deg, right_deg, heading_deg)`` returns the two duties (None = release);
    ``openbricks_native.DriveBase.update`` fits as is when the rig passes the heading (``gyro=True``).
    ``silent`` names wheels whose reading is withheld (None) from a given time on.
    """

    controller: Callable[..., tuple[float | None, float | None]]
    chassis: Chassis = field(default_factory=Chassis)
    gyro: bool = False
    now_ms: int = 0
    silent: dict[int, int] = field(default_factory=dict)
    trace: list[Sample] = field(default_factory=list)

    def period(self) -> tuple[float | None, float | None]:
        left, right = self.chassis.encoders_deg
        if self.silent.get(0, math.inf) <= self.now_ms:
            left = None
        if self.silent.get(1, math.inf) <= self.now_ms:
            right = None
        if self.gyro:
            duties = self.controller(self.now_ms, left, right, self.chassis.heading_deg)
        else:
            duties = self.controller(self.now_ms, left, right)
        self.chassis.step(duties, PERIOD_MS / 1000.0)
        self.now_ms += PERIOD_MS
        c = self.chassis
        self.trace.append(Sample(self.now_ms, duties, c.x_mm, c.y_mm, c.heading_deg, c.speeds_dps))
        return duties

    def run(self, duration_ms: int) -> None:
        for _ in range(duration_ms // PERIOD_MS):
            self.period()

    def run_until(self, predicate: Callable[[], bool], timeout_ms: int) -> int:
        """Run until predicate() holds; returns the elapsed ms. Fails the test on timeout."""
        start = self.now_ms
        while not predicate():
            assert self.now_ms - start < timeout_ms, f"not reached within {timeout_ms} ms"
            self.period()
        return self.now_ms - start
