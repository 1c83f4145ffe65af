"""A season's table made the way a team makes one: a PNG of the printed mat and a world file beside it.

The mat is 2362 x 1143 mm drawn at 1 px/mm with exact pixel edges, so a test knows where every edge
is printed: a 20 mm black line along y = 571 mm (lower-left origin) from x = 150 to 2150 mm, and four
100 mm colour patches in a row below it.
"""

from pathlib import Path

import numpy as np

SIZE_MM = (2362, 1143)
PAPER = (246, 246, 242)
INK = (22, 22, 24)
LINE_Y_MM = (561, 581)  # the line's lower and upper edge
LINE_X_MM = (150, 2150)
# name -> (x0, y0) lower-left corner of a 100 mm patch
PATCHES = {
    "red": ((205, 35, 45), (400, 250)),
    "green": ((30, 150, 70), (700, 250)),
    "blue": ((30, 85, 195), (1000, 250)),
    "yellow": ((245, 205, 35), (1300, 250)),
}
PATCH_MM = 100

WORLD_TOML = """\
name = "season table"
description = "a line, four colour patches, three blocks and two zones"
mat = "mat.png"
size_mm = [2362, 1143]
start = { x_mm = 250, y_mm = 571, heading_deg = 0 }
time_limit_s = 150

[walls]
height_mm = 70
thickness_mm = 20

[slots.north]
positions = [[900, 850], [1200, 850], [1500, 850], [1800, 850], [2100, 850]]
jitter_mm = 10
jitter_deg = 8

[[props]]
name = "red_block"
colour = "red"
slots = "north"
count = 2

[[props]]
colour = "blue"
slots = "north"

[[props]]
name = "pusher_target"
colour = "green"
at = [500, 1000]

[[zones]]
name = "parking"
rect = [2000, 450, 2300, 700]

[[zones]]
name = "green_goal"
polygon = [[1000, 900], [1300, 900], [1300, 1120], [1000, 1120]]

[[scoring]]
prop = "green"
zone = "green_goal"
points = 25
label = "green block delivered"

[[scoring]]
robot = true
zone = "parking"
points = 5
"""


def draw_mat() -> np.ndarray:
    """(H, W, 3) of the mat, row 0 the far edge, 1 px per mm."""
    width, height = SIZE_MM
    pixels = np.empty((height, width, 3), dtype=np.uint8)
    pixels[:] = PAPER

    def fill(x0, y0, x1, y1, rgb):  # lower-left origin mm -> rows from the top
        pixels[height - y1 : height - y0, x0:x1] = rgb

    fill(LINE_X_MM[0], LINE_Y_MM[0], LINE_X_MM[1], LINE_Y_MM[1], INK)
    for rgb, (x0, y0) in PATCHES.values():
        fill(x0, y0, x0 + PATCH_MM, y0 + PATCH_MM, rgb)
    return pixels


def write_table(folder: Path, toml: str = WORLD_TOML) -> Path:
    """The mat PNG and the world file in folder; returns the world file's path."""
    from PIL import Image

    Image.fromarray(draw_mat()).save(folder / "mat.png")
    path = folder / "table.toml"
    path.write_text(toml)
    return path
