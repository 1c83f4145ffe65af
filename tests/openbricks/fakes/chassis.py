"""A two-wheel chassis on the fake board: the robot's pose from its wheels, and the yaw a gyro sees.

    chassis = Chassis(lambda: left_plant.angle_deg, lambda: right_plant.angle_deg,
                      wheel_diameter_mm=65, axle_track_mm=150, gyro=icm_chip)

Each wheel is given as a function returning its shaft angle in degrees, forward-positive (a motor
mounted mirror-image reads negated). Every millisecond of virtual time the chassis turns each wheel's
rotation into ground travel (less its `slip` fraction: a spinning tyre), integrates the pose and sets
the gyro chip's `yaw_rate_dps` to the body's real rotation, so a test asserts what the robot did, not
what its controller believes.

Frames: x forward at the start, y to the left; heading in degrees clockwise from above (the drive
base's convention), so a right turn makes y negative.
"""

import math

from . import clock

_STEP_US = 1000


class Chassis:
    def __init__(self, left_deg, right_deg, wheel_diameter_mm, axle_track_mm, gyro=None, slip=(0.0, 0.0)):
        self._wheels = (left_deg, right_deg)
        self.mm_per_deg = math.pi * wheel_diameter_mm / 360.0
        self.axle_track_mm = axle_track_mm
        self.gyro = gyro
        self.slip = slip
        self.x_mm = 0.0
        self.y_mm = 0.0
        self.heading_deg = 0.0
        self.travel_mm = 0.0
        self._last = [wheel() for wheel in self._wheels]
        self._steps = clock.every_us(_STEP_US, self._step)

    def _step(self):
        now = [wheel() for wheel in self._wheels]
        ground = [(now[i] - self._last[i]) * self.mm_per_deg * (1.0 - self.slip[i]) for i in (0, 1)]
        self._last = now
        forward = 0.5 * (ground[0] + ground[1])
        turn_rad = (ground[0] - ground[1]) / self.axle_track_mm
        mid = -math.radians(self.heading_deg) - 0.5 * turn_rad
        self.x_mm += forward * math.cos(mid)
        self.y_mm += forward * math.sin(mid)
        self.heading_deg += math.degrees(turn_rad)
        self.travel_mm += forward
        if self.gyro is not None:
            self.gyro.yaw_rate_dps = math.degrees(turn_rad) * 1e6 / _STEP_US

    def close(self):
        self._steps.cancel()
