"""Draws the built-in worlds' mat images once: `python -m openbricks_sim.worlds.builtin.draw_mats`.

The PNGs beside this file are its output and are what the worlds load; the simulator never runs
this. It is kept so a change to a built-in mat is a change here and a run, the way a team's own mat
is an export from its drawing program. Shapes come from the same tables the worlds score with
(line_track's route, the zones and the WRO targets), and the WRO slots from wro.toml itself.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ...world_file import load
from .. import line_track, wro, zones
from .canvas import BLACK, GREEN, GREY, WHITE, MatCanvas

HERE = Path(__file__).parent


def draw_line_track() -> MatCanvas:
    canvas = MatCanvas(*line_track.MAT_MM, background=WHITE)
    path, (jx, jy) = line_track.route()
    canvas.stroke_path(path.points(), line_track.LINE_WIDTH_MM, BLACK)
    branch = [(jx, jy), (jx, jy - line_track.BRANCH_MM)]  # the branch leaves to the right
    canvas.stroke_path(branch, line_track.LINE_WIDTH_MM, BLACK)
    across, along = line_track.FINISH_BAR_MM
    ex, ey = path.x_mm, path.y_mm  # the home straight runs toward -y
    canvas.fill_rect(ex - across / 2, ey, ex + across / 2, ey - along, BLACK)
    return canvas


def draw_zones() -> MatCanvas:
    canvas = MatCanvas(*zones.MAT_MM, background=WHITE)
    for x0, y0, x1, y1, rgb in zones.ZONES.values():
        canvas.fill_rect(x0, y0, x1, y1, rgb)
    canvas.stroke_path(zones.ALIGN_LINE_MM, zones.ALIGN_LINE_WIDTH_MM, BLACK)
    return canvas


def draw_arena() -> MatCanvas:
    # A uniform mat needs no detail: a coarse texture keeps the model small.
    return MatCanvas(1600.0, 1000.0, px_per_mm=0.05, background=(200, 200, 196))


def draw_wro() -> MatCanvas:
    spec = load(HERE / "wro.toml")
    canvas = MatCanvas(*spec.size_mm, background=WHITE)
    canvas.stroke_rect(*wro.START_AREA_MM, 15.0, GREEN)
    canvas.stroke_path(wro.GUIDE_LINE_MM, wro.LINE_WIDTH_MM, BLACK)
    for x in wro.CROSS_LINES_X_MM:
        canvas.stroke_path(
            ((x, -wro.CROSS_LINE_HALF_MM), (x, wro.CROSS_LINE_HALF_MM)), wro.LINE_WIDTH_MM, BLACK
        )
    half = wro.SLOT_SIDE_MM / 2
    for slots in spec.slots.values():
        for position in slots.positions:
            x, y = spec.to_centre(*position)
            canvas.stroke_rect(x - half, y - half, x + half, y + half, 4.0, GREY)
    half = wro.TARGET_SIDE_MM / 2
    for x, y, colour in wro.TARGETS.values():
        canvas.fill_rect(x - half, y - half, x + half, y + half, wro.COLOURS[colour])
        canvas.stroke_rect(x - half, y - half, x + half, y + half, 6.0, BLACK)
    return canvas


MATS = {"line_track": draw_line_track, "zones": draw_zones, "arena": draw_arena, "wro": draw_wro}


def save(canvas: MatCanvas, path: Path) -> None:
    from PIL import Image

    # A palette PNG: the mats are a few flat colours and their anti-aliased edges, so an 8-bit
    # palette keeps every texel exact where it has at most 256 colours, and the file small.
    pixels = np.ascontiguousarray(canvas.pixels)
    image = Image.fromarray(pixels)
    colours = np.unique(pixels.reshape(-1, 3), axis=0)
    if len(colours) <= 256:
        image = image.quantize(
            colors=len(colours), method=Image.Quantize.FASTOCTREE, dither=Image.Dither.NONE
        )
        if not np.array_equal(np.asarray(image.convert("RGB")), pixels):
            image = Image.fromarray(pixels)
    image.save(path, optimize=True)


def main() -> None:
    for name, draw in MATS.items():
        path = HERE / f"{name}.png"
        save(draw(), path)
        print(f"{path}: {path.stat().st_size // 1024} KB")


if __name__ == "__main__":
    main()
