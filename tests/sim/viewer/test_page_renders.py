"""The page as a person sees it: headless Chromium opens the viewer, and screenshots of the page must show
the zones mat's coloured areas where the world puts them (so the printed canvas is neither missing
nor mirrored), beside the side panel.

The scene arrives over the page's websocket and is drawn by software WebGL, which takes a while on a
busy machine, so the browser is driven over its DevTools protocol and screenshots are taken until
the page shows the mat (or a minute has passed). Chromium is Debian's package: `make setup` installs
it (APT_PACKAGES in the Makefile)."""

import base64
import io
import json
import re
import shutil
import subprocess
import time
import urllib.request
from pathlib import Path

import numpy as np
import pytest
from PIL import Image
from websockets.sync.client import connect

from openbricks_sim.simulation import Simulation
from openbricks_sim.viewer import SimViewer

pytestmark = pytest.mark.e2e

WIDTH, HEIGHT = 1280, 800
RENDER_TIMEOUT_S = 60.0
ARTIFACTS = Path(__file__).resolve().parents[3] / "build" / "artifacts" / "sim"
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
    "--remote-debugging-address=127.0.0.1",
    "--remote-debugging-port=0",
]


class Browser:
    """Headless Chromium showing one URL, screenshotted through its DevTools websocket."""

    def __init__(self, url, profile):
        chromium = shutil.which("chromium")
        assert chromium, "Debian's chromium is needed for this test: `make setup` installs it (APT_PACKAGES)"
        self._process = subprocess.Popen(
            [chromium, *CHROMIUM_FLAGS, f"--user-data-dir={profile}", url],
            stdout=subprocess.DEVNULL,
            stderr=subprocess.PIPE,
            text=True,
        )
        try:
            devtools_port = self._devtools_port()
            with urllib.request.urlopen(f"http://127.0.0.1:{devtools_port}/json/list", timeout=10) as reply:
                targets = json.load(reply)
            page = next(t for t in targets if t["type"] == "page")
            self._socket = connect(page["webSocketDebuggerUrl"], max_size=None)
        except BaseException:
            self._process.kill()
            self._process.wait()
            raise
        self._next_id = 0
        # The window size includes the browser's own frame: pin the page's viewport instead.
        self._call(
            "Emulation.setDeviceMetricsOverride",
            {"width": WIDTH, "height": HEIGHT, "deviceScaleFactor": 1, "mobile": False},
        )

    def _devtools_port(self):
        deadline = time.monotonic() + 30
        while time.monotonic() < deadline:
            line = self._process.stderr.readline()
            found = re.search(r"DevTools listening on ws://127\.0\.0\.1:(\d+)/", line)
            if found:
                return int(found.group(1))
            if not line and self._process.poll() is not None:
                break
        raise AssertionError("chromium did not open its DevTools port")

    def screenshot(self):
        png = base64.b64decode(self._call("Page.captureScreenshot")["data"])
        return np.asarray(Image.open(io.BytesIO(png)).convert("RGB")).astype(int)

    def _call(self, method, params=None):
        self._next_id += 1
        self._socket.send(json.dumps({"id": self._next_id, "method": method, "params": params or {}}))
        while True:
            reply = json.loads(self._socket.recv(timeout=30))
            if reply.get("id") == self._next_id:
                assert "error" not in reply, reply
                return reply["result"]

    def close(self):
        self._socket.close()
        self._process.terminate()
        try:
            self._process.wait(timeout=10)
        except subprocess.TimeoutExpired:
            self._process.kill()
            self._process.wait()


def centroid(mask):
    rows, cols = np.nonzero(mask)
    return rows.mean(), cols.mean()


def zones_seen(pixels):
    """Pixel masks of the mat's coloured zones, within the scene (clear of the panel and notices)."""
    height, width = pixels.shape[:2]
    scene = np.zeros((height, width), dtype=bool)
    scene[int(0.25 * height) : int(0.85 * height), int(0.2 * width) : int(0.72 * width)] = True
    r, g, b = pixels[..., 0], pixels[..., 1], pixels[..., 2]
    masks = {
        "red": (r > g + 80) & (r > b + 80),
        "green": (g > r + 50) & (g > b + 40),
        "blue": (b > r + 80) & (b > g + 40),
        "yellow": (r > b + 80) & (g > b + 80),
    }
    return {name: mask & scene for name, mask in masks.items()}


def test_the_zones_mat_renders_with_its_colours_in_place(tmp_path):
    sim = Simulation("zones", "st3032", epoch_ms=0)
    try:
        with SimViewer(port=0, controls=False) as viewer:
            viewer.show_still(sim, "preview")
            browser = Browser(viewer.url, tmp_path / "profile")
            try:
                deadline = time.monotonic() + RENDER_TIMEOUT_S
                while True:
                    pixels = browser.screenshot()
                    seen = zones_seen(pixels)
                    if all(mask.sum() > 800 for mask in seen.values()) or time.monotonic() > deadline:
                        break
                    time.sleep(1.0)
            finally:
                browser.close()
    finally:
        sim.close()
    # Kept for a person to look at, and for the simulator guide's picture of the 3D view (docs/conf.py).
    ARTIFACTS.mkdir(parents=True, exist_ok=True)
    Image.fromarray(pixels.astype(np.uint8)).save(ARTIFACTS / "viewer-3d.png")
    assert pixels.shape[:2] == (HEIGHT, WIDTH)
    for name, mask in seen.items():
        assert mask.sum() > 800, f"the {name} zone is missing from the page ({mask.sum()} pixels)"
    where = {name: centroid(mask) for name, mask in seen.items()}
    # Seen from the south: north (+y) is up the screen, east (+x) to the right.
    assert where["green"][0] < where["red"][0] < where["blue"][0], "the mat is mirrored north-south"
    assert where["yellow"][1] < where["red"][1], "the mat is mirrored east-west"
    # The side panel: a light column on the right (a preview has no run controls to colour it).
    panel = pixels[int(0.1 * HEIGHT) : int(0.3 * HEIGHT), int(0.76 * WIDTH) : int(0.97 * WIDTH)]
    assert (panel.min(axis=2) > 230).mean() > 0.5, "no side panel"
