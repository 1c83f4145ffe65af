"""What a world's scoring hook sees: the final pose of the robot and of every prop.

A hook is a plain function FinalState -> dict of JSON-friendly values, so a
batch of seeded runs can be tabulated without knowing the world. Poses are
in the mat's millimetre frame with Pybricks headings (clockwise from +x).
"""

import math
from collections.abc import Callable
from dataclasses import dataclass, field

import mujoco

from ..chassis import ROBOT_BODY

PROP_PREFIX = "prop_"


@dataclass(frozen=True)
class Pose:
    x_mm: float
    y_mm: float
    heading_deg: float  # clockwise from +x


@dataclass(frozen=True)
class FinalState:
    robot: Pose | None  # None when the world was stepped without a robot
    props: dict[str, Pose] = field(default_factory=dict)
    time_s: float = 0.0


Scoring = Callable[[FinalState], dict]


def body_pose(data: mujoco.MjData, body_id: int) -> Pose:
    x, y = data.xpos[body_id][:2]
    w, qx, qy, qz = data.xquat[body_id]
    yaw = math.atan2(2.0 * (w * qz + qx * qy), 1.0 - 2.0 * (qy * qy + qz * qz))
    return Pose(float(x) * 1000.0, float(y) * 1000.0, -math.degrees(yaw))


def final_state(model: mujoco.MjModel, data: mujoco.MjData) -> FinalState:
    """Read the robot and the props (bodies named prop_*) out of a stepped simulation."""
    robot_id = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, ROBOT_BODY)
    props = {}
    for body_id in range(model.nbody):
        name = mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_BODY, body_id)
        if name and name.startswith(PROP_PREFIX):
            props[name] = body_pose(data, body_id)
    robot = body_pose(data, robot_id) if robot_id >= 0 else None
    return FinalState(robot=robot, props=props, time_s=float(data.time))
