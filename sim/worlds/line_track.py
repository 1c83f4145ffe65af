"""A line-following track: 20 mm black line on a white 2000 x 1200 mm mat.

The route runs from a start straight through a left and two right bends,
past a junction where a side branch leaves to the right, to a finish bar
across the line. The branch is on the right on purpose: a left-edge follower
(QTRLineSensor "left" mode) holds the main line's left edge straight through
it, while a right-edge follower would take it, the classic junction choice.
The finish bar is wider than the QTR window, so the whole window going dark
is the stop signal, as the manual's followers use it.

The world itself is builtin/line_track.toml and its mat image, drawn from route() by
builtin/draw_mats.py; this module keeps the route, which scores a run.
"""

from .path import Path
from .scoring import FinalState

MAT_MM = (2000.0, 1200.0)
LINE_WIDTH_MM = 20.0
FINISH_BAR_MM = (160.0, 40.0)  # across the line, along the line
BRANCH_MM = 180.0
# The finish counts when the robot stops with its axle within this much of the bar's near edge
# (a QTR bar 70 mm ahead of the axle over the bar puts the axle about 70 mm short of it).
FINISH_WINDOW_MM = 150.0
MAX_OFF_LINE_MM = 60.0


def route() -> tuple[Path, tuple[float, float]]:
    """The main line's centreline, and where the side branch leaves it."""
    path = Path(-900.0, -400.0, 0.0)
    path.straight(600.0)  # start straight
    path.arc(250.0, -90.0)  # left bend, now heading up the mat
    path.straight(250.0)
    path.arc(250.0, 90.0)  # right bend, heading +x again
    junction = (path.x_mm + 150.0, path.y_mm)
    path.straight(350.0)  # past the junction
    path.arc(250.0, 90.0)  # right bend, heading down the mat
    path.straight(350.0)  # home straight into the finish bar
    return path, junction


def score(state: FinalState) -> dict:
    """How far along the line the robot got, and whether it stopped at the finish bar."""
    path, _ = route()
    if state.robot is None:
        return {"finished": False, "progress_mm": 0.0, "progress_pct": 0.0, "off_line_mm": None}
    along, off = path.progress(state.robot.x_mm, state.robot.y_mm)
    finished = along >= path.length_mm - FINISH_WINDOW_MM and off <= MAX_OFF_LINE_MM
    return {
        "finished": bool(finished),
        "progress_mm": round(along, 1),
        "progress_pct": round(100.0 * along / path.length_mm, 1),
        "off_line_mm": round(off, 1),
    }
