"""One picture of the simulated world, taken between physics steps for the viewer to draw later.

MuJoCo steps with the GIL released, so another thread must never read the live mjData: it could see
half a step. A Frame copies what the viewer needs (every body's placement, the robot's pose, the
clock) on the simulation's own thread, and the drawing thread only ever reads Frames.
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class Frame:
    sim_ms: int
    wall_s: float  # time.perf_counter() when taken: the real-time factor is measured between frames
    body_xpos: np.ndarray  # (nbody, 3) world positions, metres
    body_xmat: np.ndarray  # (nbody, 3, 3) world orientations
    qpos: np.ndarray  # for the optional contact/force overlays, which re-run kinematics on a copy
    qvel: np.ndarray
    x_mm: float
    y_mm: float
    heading_deg: float  # clockwise from +x, as the manual writes headings
    display: object = None  # the OLED's Picture (sim/display.py) once the program drew on it


def capture(simulation) -> Frame:
    """The world as it is now. Call only from the thread that steps the simulation."""
    physics = simulation.physics
    data = physics.data
    pose = physics.pose()
    return Frame(
        sim_ms=simulation.clock.now_ms(),
        wall_s=time.perf_counter(),
        body_xpos=np.array(data.xpos, copy=True),
        body_xmat=np.array(data.xmat, copy=True).reshape(-1, 3, 3),
        qpos=np.array(data.qpos, copy=True),
        qvel=np.array(data.qvel, copy=True),
        x_mm=pose.x_mm,
        y_mm=pose.y_mm,
        heading_deg=pose.heading_deg,
        display=_display(simulation),
    )


def _display(simulation):
    oled = getattr(getattr(simulation, "sensors", None), "oled", None)
    return oled.picture() if oled is not None and oled.writes else None
