"""A WRO-size competition table: a 2362 x 1143 mm printed mat inside border walls, with a dozen
coloured blocks to sort.

The mat is printed in the style of a RoboMission table: a start area at
the west end, a black guide line down the middle with three cross lines, two
rows of six grey-outlined prop slots, and eight coloured target squares
(red, green, blue, yellow along the north edge, mirrored along the south).
Twelve blocks, three per colour, sit on the slots. A seed shuffles which
colour goes on which slot and nudges each block within its slot (a "robot
round" randomisation): the same seed always gives the same table.

Scoring: 10 points per block whose centre lies inside a target square of its
own colour.

The table itself (size, walls, slots, blocks and their draw) is builtin/wro.toml; its mat image is
drawn by builtin/draw_mats.py from the tables below, which also score.
"""

from ..world_file import PALETTE
from .scoring import FinalState

LINE_WIDTH_MM = 20.0
COLOURS = {c: PALETTE[c] for c in ("red", "green", "blue", "yellow")}

START_AREA_MM = (-1161.0, -150.0, -861.0, 150.0)
GUIDE_LINE_MM = ((-850.0, 0.0), (1000.0, 0.0))
CROSS_LINES_X_MM = (-480.0, 0.0, 480.0)
CROSS_LINE_HALF_MM = 420.0

SLOT_SIDE_MM = 70.0

TARGET_SIDE_MM = 180.0
TARGET_XS_MM = (-600.0, -200.0, 200.0, 600.0)
TARGET_Y_MM = 430.0
# name -> (centre x, centre y, colour name)
TARGETS = {
    **{f"north_{c}": (x, TARGET_Y_MM, c) for x, c in zip(TARGET_XS_MM, COLOURS, strict=True)},
    **{f"south_{c}": (x, -TARGET_Y_MM, c) for x, c in zip(TARGET_XS_MM, reversed(COLOURS), strict=True)},
}
POINTS_PER_BLOCK = 10


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
