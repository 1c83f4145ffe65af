"""A flat, featureless floor: the reference benchmark world and the fidelity tests' ground."""

import mujoco

from .scene import new_scene


def build(seed: int = 0) -> mujoco.MjSpec:
    spec = new_scene("empty")
    spec.worldbody.add_geom(
        name="floor",
        type=mujoco.mjtGeom.mjGEOM_PLANE,
        size=[5.0, 5.0, 0.1],
        rgba=[0.85, 0.85, 0.85, 1.0],
    )
    return spec
