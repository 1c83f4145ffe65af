"""A robot standing in a world at a chosen pose, settled on its wheels: the scene sensor tests read."""

import math

import mujoco

from openbricks_sim.chassis import CHASSIS, add_chassis
from openbricks_sim.worlds import WORLDS


def place(alias, x_mm, y_mm, heading_deg=0.0, chassis="st3032", seed=0):
    spec = WORLDS[alias].build(seed)
    add_chassis(spec, CHASSIS[chassis], x_mm, y_mm, heading_deg)
    model = spec.compile()
    data = mujoco.MjData(model)
    mujoco.mj_step(model, data, nstep=100)
    return model, data


def step_ms(model, data, ms):
    mujoco.mj_step(model, data, nstep=int(ms))


def spin_in_place(model, data, ms, wheel_dps=200.0, gain=0.3):
    """Drive the wheels in opposite directions with a plain speed loop: a clockwise spin for
    positive wheel_dps (left wheel forward)."""
    wheels = [model.joint(name).dofadr[0] for name in ("left_wheel", "right_wheel")]
    target = (math.radians(wheel_dps), -math.radians(wheel_dps))
    for _ in range(int(ms)):
        for i, dof in enumerate(wheels):
            data.ctrl[i] = gain * (target[i] - data.qvel[dof])
        mujoco.mj_step(model, data)
