"""A walled arena for the distance sensors: 1600 x 1000 mm of plain mat inside 100 mm walls.

The robot starts at the west end facing the east wall 1300 mm ahead; a square
pillar stands off the direct path so a sweeping or turning robot has a near
target too. Scoring reports how close the robot ended to the walls, for
"drive up to the wall and stop at N mm" missions. The world is builtin/arena.toml;
the faces scored here are its walls and pillar (a test keeps the two in step).
"""

import math

from .scoring import FinalState

INNER_MM = (1600.0, 1000.0)
PILLAR_MM = (300.0, 250.0, 200.0)  # centre x, centre y, side


def _faces():
    """Every vertical face as an axis-aligned box (x0, y0, x1, y1) in mm: the inside of the walls and
    the pillar."""
    hw, hh = INNER_MM[0] / 2, INNER_MM[1] / 2
    px, py, side = PILLAR_MM
    big = 1e6
    return [
        (-big, hh, big, big),
        (-big, -big, big, -hh),
        (hw, -big, big, big),
        (-big, -big, -hw, big),
        (px - side / 2, py - side / 2, px + side / 2, py + side / 2),
    ]


def _distance_to_box(x, y, box):
    x0, y0, x1, y1 = box
    dx = max(x0 - x, 0.0, x - x1)
    dy = max(y0 - y, 0.0, y - y1)
    return math.hypot(dx, dy)


def _ray_to_box(x, y, ux, uy, box):
    """Distance along the unit ray (ux, uy) from (x, y) to an axis-aligned box, or None."""
    x0, y0, x1, y1 = box
    near, far = -math.inf, math.inf
    for origin, direction, lo, hi in ((x, ux, x0, x1), (y, uy, y0, y1)):
        if abs(direction) < 1e-12:
            if not lo <= origin <= hi:
                return None
            continue
        t0, t1 = (lo - origin) / direction, (hi - origin) / direction
        near, far = max(near, min(t0, t1)), min(far, max(t0, t1))
    if near > far or far < 0:
        return None
    return max(near, 0.0)


def score(state: FinalState) -> dict:
    """Distance from the robot's centre to the nearest wall face, and to the first face straight ahead."""
    if state.robot is None:
        return {"nearest_wall_mm": None, "ahead_mm": None}
    x, y = state.robot.x_mm, state.robot.y_mm
    heading = -math.radians(state.robot.heading_deg)
    ux, uy = math.cos(heading), math.sin(heading)
    faces = _faces()
    nearest = min(_distance_to_box(x, y, box) for box in faces)
    hits = [d for d in (_ray_to_box(x, y, ux, uy, box) for box in faces) if d is not None]
    return {"nearest_wall_mm": round(nearest, 1), "ahead_mm": round(min(hits), 1) if hits else None}
