"""The page as a person sees it: headless Chromium opens the viewer and takes a screenshot, and the zones
mat must show its coloured areas where the world puts them (so the printed canvas is neither missing
nor mirrored) with the side panel beside the scene.

Chromium comes from Debian's package (`make setup` installs it: APT_PACKAGES in the Makefile)."""

import shutil
import subprocess

import numpy as np
import pytest
from PIL import Image

from openbricks_sim.simulation import Simulation
from openbricks_sim.viewer import SimViewer

pytestmark = pytest.mark.e2e

WIDTH, HEIGHT = 1280, 800
CHROMIUM_FLAGS = [
    "--headless",
    "--no-sandbox",
    "--disable-gpu",
    "--no-first-run",
    "--disable-background-networking",
    "--disable-component-update",
    "--disable-sync",
    "--hide-scrollbars",
    f"--window-size={WIDTH},{HEIGHT}",
    # Virtual time runs ahead while the page is idle: the scene has arrived and drawn well within it.
    "--virtual-time-budget=8000",
]


def screenshot(url, folder):
    chromium = shutil.which("chromium")
    assert chromium, "Debian's chromium is needed for this test: `make setup` installs it (APT_PACKAGES)"
    path = folder / "page.png"
    subprocess.run(
        [chromium, *CHROMIUM_FLAGS, f"--user-data-dir={folder / 'profile'}", f"--screenshot={path}", url],
        capture_output=True,
        timeout=180,
        check=True,
    )
    return np.asarray(Image.open(path).convert("RGB")).astype(int)


def centroid(mask):
    rows, cols = np.nonzero(mask)
    return rows.mean(), cols.mean()


def test_the_zones_mat_renders_with_its_colours_in_place(tmp_path):
    sim = Simulation("zones", "st3032", epoch_ms=0)
    try:
        with SimViewer(port=0, controls=False) as viewer:
            viewer.show_still(sim, "preview")
            pixels = screenshot(viewer.url, tmp_path)
    finally:
        sim.close()
    assert pixels.shape[:2] == (HEIGHT, WIDTH)
    # The scene, clear of the side panel (right) and of the browser's notices (top left).
    scene = np.zeros(pixels.shape[:2], dtype=bool)
    scene[int(0.25 * HEIGHT) : int(0.85 * HEIGHT), int(0.2 * WIDTH) : int(0.72 * WIDTH)] = True
    r, g, b = pixels[..., 0], pixels[..., 1], pixels[..., 2]
    zones = {
        "red": (r > g + 80) & (r > b + 80),
        "green": (g > r + 50) & (g > b + 40),
        "blue": (b > r + 80) & (b > g + 40),
        "yellow": (r > b + 80) & (g > b + 80),
    }
    seen = {name: mask & scene for name, mask in zones.items()}
    for name, mask in seen.items():
        assert mask.sum() > 800, f"the {name} zone is missing from the page ({mask.sum()} pixels)"
    where = {name: centroid(mask) for name, mask in seen.items()}
    # Seen from the south: north (+y) is up the screen, east (+x) to the right.
    assert where["green"][0] < where["red"][0] < where["blue"][0], "the mat is mirrored north-south"
    assert where["yellow"][1] < where["red"][1], "the mat is mirrored east-west"
    # The side panel is drawn: a light column on the right with the brand-blue buttons hidden (no
    # controls in a preview), so mostly near-white.
    panel = pixels[int(0.1 * HEIGHT) : int(0.3 * HEIGHT), int(0.76 * WIDTH) : int(0.97 * WIDTH)]
    assert (panel.min(axis=2) > 230).mean() > 0.5, "no side panel"
