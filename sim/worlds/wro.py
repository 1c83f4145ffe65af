"""A WRO-size competition table: a 2362 x 1143 mm printed mat inside border walls, with a dozen
coloured blocks to sort.

The mat is drawn by code in the style of a RoboMission print: a start area at
the west end, a black guide line down the middle with three cross lines, two
rows of six grey-outlined prop slots, and eight coloured target squares
(red, green, blue, yellow along the north edge, mirrored along the south).
Twelve blocks, three per colour, sit on the slots. A seed shuffles which
colour goes on which slot and nudges each block within its slot (a "robot
round" randomisation): the same seed always gives the same table.

Scoring: 10 points per block whose centre lies inside a target square of its
own colour.
"""

import mujoco
import numpy as np

from .canvas import BLACK, BLUE, GREEN, GREY, RED, WHITE, YELLOW, MatCanvas
from .props import BLOCK, add_prop, prop_name
from .scene import new_scene
from .scoring import FinalState
from .table import add_border, add_floor, add_mat

MAT_MM = (2362.0, 1143.0)
WALL_HEIGHT_MM = 70.0
LINE_WIDTH_MM = 20.0
COLOURS = {"red": RED, "green": GREEN, "blue": BLUE, "yellow": YELLOW}

START_AREA_MM = (-1161.0, -150.0, -861.0, 150.0)
START_MM_DEG = (-1011.0, 0.0, 0.0)
GUIDE_LINE_MM = ((-850.0, 0.0), (1000.0, 0.0))
CROSS_LINES_X_MM = (-480.0, 0.0, 480.0)
CROSS_LINE_HALF_MM = 420.0

SLOT_XS_MM = (-600.0, -360.0, -120.0, 120.0, 360.0, 600.0)
SLOT_YS_MM = (170.0, -170.0)
SLOT_SIDE_MM = 70.0
SLOT_JITTER_MM = 8.0
SLOT_JITTER_DEG = 10.0
BLOCKS_PER_COLOUR = 3

TARGET_SIDE_MM = 180.0
TARGET_XS_MM = (-600.0, -200.0, 200.0, 600.0)
TARGET_Y_MM = 430.0
# name -> (centre x, centre y, colour name)
TARGETS = {
    **{f"north_{c}": (x, TARGET_Y_MM, c) for x, c in zip(TARGET_XS_MM, COLOURS, strict=True)},
    **{f"south_{c}": (x, -TARGET_Y_MM, c) for x, c in zip(TARGET_XS_MM, reversed(COLOURS), strict=True)},
}
POINTS_PER_BLOCK = 10


def slots_mm() -> list[tuple[float, float]]:
    return [(x, y) for y in SLOT_YS_MM for x in SLOT_XS_MM]


def draw(px_per_mm: float = 1.0) -> MatCanvas:
    canvas = MatCanvas(*MAT_MM, px_per_mm=px_per_mm, background=WHITE)
    canvas.stroke_rect(*START_AREA_MM, 15.0, GREEN)
    canvas.stroke_path(GUIDE_LINE_MM, LINE_WIDTH_MM, BLACK)
    for x in CROSS_LINES_X_MM:
        canvas.stroke_path(((x, -CROSS_LINE_HALF_MM), (x, CROSS_LINE_HALF_MM)), LINE_WIDTH_MM, BLACK)
    half = SLOT_SIDE_MM / 2
    for x, y in slots_mm():
        canvas.stroke_rect(x - half, y - half, x + half, y + half, 4.0, GREY)
    half = TARGET_SIDE_MM / 2
    for x, y, colour in TARGETS.values():
        canvas.fill_rect(x - half, y - half, x + half, y + half, COLOURS[colour])
        canvas.stroke_rect(x - half, y - half, x + half, y + half, 6.0, BLACK)
    return canvas


def layout(seed: int) -> list[tuple[str, float, float, float]]:
    """(colour, x_mm, y_mm, yaw_deg) of every block for this seed."""
    rng = np.random.default_rng(seed)
    colours = [c for c in COLOURS for _ in range(BLOCKS_PER_COLOUR)]
    order = rng.permutation(len(colours))
    blocks = []
    for (x, y), i in zip(slots_mm(), order, strict=True):
        dx, dy = rng.uniform(-SLOT_JITTER_MM, SLOT_JITTER_MM, size=2)
        yaw = rng.uniform(-SLOT_JITTER_DEG, SLOT_JITTER_DEG)
        blocks.append((colours[i], float(x + dx), float(y + dy), float(yaw)))
    return blocks


def build(seed: int = 0) -> mujoco.MjSpec:
    spec = new_scene("wro")
    # Resting blocks sleep until touched: twelve idle props then cost next to nothing per step.
    spec.option.enableflags |= mujoco.mjtEnableBit.mjENBL_SLEEP
    add_floor(spec)
    add_mat(spec, draw())
    add_border(spec, *MAT_MM, height_mm=WALL_HEIGHT_MM)
    for index, (colour, x, y, yaw) in enumerate(layout(seed)):
        add_prop(spec, prop_name(index, colour), BLOCK, COLOURS[colour], x, y, yaw)
    return spec


def target_at(x_mm: float, y_mm: float) -> str | None:
    half = TARGET_SIDE_MM / 2
    for name, (x, y, _colour) in TARGETS.items():
        if abs(x_mm - x) <= half and abs(y_mm - y) <= half:
            return name
    return None


def score(state: FinalState) -> dict:
    """Points for blocks sorted into a target of their own colour; where every block ended."""
    placed = {}
    points = 0
    for name, pose in sorted(state.props.items()):
        target = target_at(pose.x_mm, pose.y_mm)
        placed[name] = target
        if target is not None and TARGETS[target][2] == name.rsplit("_", 1)[-1]:
            points += POINTS_PER_BLOCK
    return {
        "points": points,
        "sorted": points // POINTS_PER_BLOCK,
        "in_wrong_target": sum(
            1 for name, t in placed.items() if t is not None and TARGETS[t][2] != name.rsplit("_", 1)[-1]
        ),
        "targets": placed,
    }
