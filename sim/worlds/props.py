"""Movable props: rigid blocks with real mass and friction that a robot can push.

Props start asleep (MuJoCo's sleeping islands) and wake when something
touches them, so a table full of props costs almost nothing until the robot
reaches one; that is what keeps a competition table well above real time.
Their geoms take contact priority over the mat, so a prop slides with its own
friction (plastic on printed vinyl) rather than the mat's default.
"""

import math
from dataclasses import dataclass

import mujoco

from .scoring import PROP_PREFIX

MM = 0.001


@dataclass(frozen=True)
class PropKind:
    size_mm: tuple[float, float, float]  # x, y, z extents
    mass_kg: float
    friction: float  # sliding coefficient against the mat



def prop_name(index: int, label: str) -> str:
    return f"{PROP_PREFIX}{index:02d}_{label}"


def add_prop(spec: mujoco.MjSpec, name: str, kind: PropKind, rgb, x_mm, y_mm, yaw_deg=0.0):
    """A free block resting on the mat at (x_mm, y_mm), turned yaw_deg clockwise."""
    sx, sy, sz = kind.size_mm
    yaw = -math.radians(yaw_deg)
    body = spec.worldbody.add_body(
        name=name,
        pos=[x_mm * MM, y_mm * MM, sz / 2 * MM],
        quat=[math.cos(yaw / 2), 0.0, 0.0, math.sin(yaw / 2)],
    )
    body.sleep = mujoco.mjtSleepPolicy.mjSLEEP_INIT
    body.add_freejoint(name=f"{name}_free")
    body.add_geom(
        name=name,
        type=mujoco.mjtGeom.mjGEOM_BOX,
        size=[sx / 2 * MM, sy / 2 * MM, sz / 2 * MM],
        mass=kind.mass_kg,
        friction=[kind.friction, 0.005, 0.0001],
        priority=1,
        condim=3,
        rgba=[c / 255 for c in rgb] + [1.0],
    )
    return body
