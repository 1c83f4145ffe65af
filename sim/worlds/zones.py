"""A zones mat: coloured areas on a white 1500 x 1000 mm mat, and a black line to align on.

The robot starts at the left facing +x. Straight ahead, past a slightly skewed
black line (the square-up exercise for the QTR bar or two colour sensors),
lies the red zone, flanked by green and blue; yellow and black sit midfield
above and below the robot's path. Scoring names the zone the robot's centre
ends in. The world is builtin/zones.toml and its mat image, drawn from ZONES by
builtin/draw_mats.py.
"""

from ..world_file import PALETTE
from .scoring import FinalState

BLACK, BLUE, GREEN, RED, YELLOW = (PALETTE[c] for c in ("black", "blue", "green", "red", "yellow"))

MAT_MM = (1500.0, 1000.0)

# name -> (x0, y0, x1, y1, colour), mat millimetres.
ZONES = {
    "red": (300.0, -120.0, 700.0, 120.0, RED),
    "green": (300.0, 160.0, 700.0, 450.0, GREEN),
    "blue": (300.0, -450.0, 700.0, -160.0, BLUE),
    "yellow": (-150.0, 250.0, 150.0, 450.0, YELLOW),
    "black": (-150.0, -450.0, 150.0, -250.0, BLACK),
}
# The align line crosses the robot's path about 250 mm ahead of the colour sensors, skewed by
# about 6 degrees so that squaring up on it is a visible correction; it stops short of the
# yellow and black zones so that every band on the mat is one colour.
ALIGN_LINE_MM = ((-203.0, -230.0), (-157.0, 230.0))
ALIGN_LINE_WIDTH_MM = 25.0


def zone_at(x_mm: float, y_mm: float) -> str | None:
    for name, (x0, y0, x1, y1, _rgb) in ZONES.items():
        if x0 <= x_mm <= x1 and y0 <= y_mm <= y1:
            return name
    return None


def score(state: FinalState) -> dict:
    """The zone under the robot's centre at the end (None: on white mat or off it)."""
    if state.robot is None:
        return {"zone": None}
    return {"zone": zone_at(state.robot.x_mm, state.robot.y_mm)}
