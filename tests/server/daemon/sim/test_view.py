"""A sim run's 3D view and its replay, through the daemon's own port, in Debian's Chromium.

The run's viser server listens on 127.0.0.1 only; the daemon forwards its page and WebSocket to a
browser signed in with a viewer's token, and refuses one without. After the run the recording plays
back in viser's own client, scrubbed to its end, where the robot stands where the run left it.
Screenshots are kept in build/artifacts/sim/."""

from __future__ import annotations

import io
import time
from pathlib import Path

import msgspec
import numpy as np
import pytest
import zstandard
from PIL import Image
from websockets.exceptions import InvalidStatus
from websockets.sync.client import connect

from tests.server.daemon.routers.test_sim import ended, save, start, wait_until
from tests.server.daemon.sim.proc_net import connections_to, listening_addresses
from tests.web.conftest import browser  # noqa: F401 - Debian's Chromium, the fixture

pytestmark = pytest.mark.e2e

ARTIFACTS = Path(__file__).resolve().parents[4] / "build" / "artifacts" / "sim"
DRAW_TIMEOUT_S = 90.0
SCREENSHOT_TIMEOUT_S = 120.0  # software WebGL on a loaded machine takes its time over one frame
DRIVE_THEN_PARK = """\
import time
from openbricks.drivers.st3032 import ST3032Motor
from openbricks.robotics import DriveBase

left = ST3032Motor(servo_id=1, uart_id=1, tx=14, rx=41)
right = ST3032Motor(servo_id=2, uart_id=1, tx=14, rx=41, invert=True)
db = DriveBase(left, right, wheel_diameter_mm=88, axle_track_mm=138)
db.straight(200)
db.stop(then="brake")
print("parked")
time.sleep_ms(600000)
"""


def drawn(png: bytes) -> bool:
    """The page shows a drawn scene: the middle of the canvas is far from one flat colour."""
    image = np.asarray(Image.open(io.BytesIO(png)).convert("RGB"), dtype=np.float32)
    h, w, _ = image.shape
    middle = image[h // 4 : 3 * h // 4, w // 8 : 5 * w // 8]
    colours = len(np.unique(middle.reshape(-1, 3).astype(np.uint8), axis=0))
    return middle.std() > 12 and colours > 200


def screenshot_when_drawn(page, name: str) -> bytes:
    deadline = time.monotonic() + DRAW_TIMEOUT_S
    while True:
        png = page.screenshot(timeout=SCREENSHOT_TIMEOUT_S * 1000)
        if drawn(png) or time.monotonic() > deadline:
            break
        time.sleep(1.0)
    ARTIFACTS.mkdir(parents=True, exist_ok=True)
    (ARTIFACTS / name).write_bytes(png)
    assert drawn(png), f"nothing drawn after {DRAW_TIMEOUT_S:g} s: see {ARTIFACTS / name}"
    return png


def robot_track(recording: bytes) -> list[np.ndarray]:
    """Every position the recording gives the robot's body, in order (metres, world frame)."""
    size = int.from_bytes(recording[:8], "little")
    inner = zstandard.ZstdDecompressor().decompress(recording[8:], max_output_size=size)
    length = int.from_bytes(inner[:8], "little")
    data = msgspec.msgpack.decode(inner[8 : 8 + length])
    offsets, offset = [], 8 + length
    for n in data["binaryBufferLengths"]:
        offset += (8 - offset % 8) % 8
        offsets.append(offset)
        offset += n
    track = []
    for _t, message in data["messages"]:
        update = message.get("updates", {}).get("batched_positions")
        if message.get("name", "").startswith("/bodies/robot/") and update:
            index = update["__binary_index"]
            raw = inner[offsets[index] : offsets[index] + data["binaryBufferLengths"][index]]
            track.append(np.frombuffer(raw, dtype=update["dtype"]).reshape(-1, 3)[0])
    return track


def test_the_view_is_served_through_the_daemon_only_and_replays_where_the_run_ended(
    daemon,
    operator,
    viewer_token,
    browser,  # noqa: F811 - the fixture, used
):
    save(operator, "park.py", DRIVE_THEN_PARK)
    run = start(operator, program="park.py", world="empty", speed=1.0, limit_ms=600_000)
    run_id = run["run_id"]
    view = f"{daemon.url}/sim/runs/{run_id}/view/"
    wait_until(operator, run_id, lambda r: r["state"] == "running" or ended(r))
    job = daemon.ctx.sim.live[run_id]
    assert listening_addresses(job.port) == {"127.0.0.1"}  # viser itself: loopback only

    # No token: neither the page nor its WebSocket.
    with daemon.client(token="not-a-token") as stranger:
        assert stranger.get(f"/sim/runs/{run_id}/view/").status_code == 401
    ws_url = view.replace("http://", "ws://").rstrip("/")
    with pytest.raises(InvalidStatus) as refused:
        connect(ws_url, origin=daemon.origin, open_timeout=10)
    assert refused.value.response.status_code == 401
    # A viewer's token (as a script sends it) gets the page and the scene's stream.
    with daemon.client(viewer_token) as watcher:
        page = watcher.get(f"/sim/runs/{run_id}/view/")
        assert page.status_code == 200 and "<html" in page.text.lower()
    with connect(
        ws_url,
        origin=daemon.origin,
        additional_headers={"Authorization": f"Bearer {viewer_token}"},
        subprotocols=["viser-v" + __import__("viser").__version__],
        open_timeout=10,
        max_size=None,
    ) as socket:
        assert isinstance(socket.recv(timeout=20), bytes)  # viser's scene, through the daemon

    # A person with the viewer's link: signed in by ?token=, the page draws the world.
    context = browser.new_context(viewport={"width": 960, "height": 600})
    context.set_default_timeout(SCREENSHOT_TIMEOUT_S * 1000)  # a page busy drawing answers slowly
    try:
        live = context.new_page()
        live.goto(f"{view}?token={viewer_token}")
        assert live.url == view  # the token was traded for the cookie and left the address bar
        wait_until(operator, run_id, lambda r: r["sim_ms"] > 4000 or ended(r), timeout_s=120)
        screenshot_when_drawn(live, "live-view.png")
        # A second watcher joins late: it is sent the scene built so far, over the same one connection
        # to the run's viser server (viser encodes each frame once per connection, in the run).
        with connect(
            ws_url,
            origin=daemon.origin,
            additional_headers={"Authorization": f"Bearer {viewer_token}"},
            subprotocols=["viser-v" + __import__("viser").__version__],
            open_timeout=10,
            max_size=None,
        ) as late:
            assert len(late.recv(timeout=20)) > 1000  # the scene's meshes, first
            assert connections_to(job.port) == 1
        live.close()

        stopped = operator.post(f"/api/sim/runs/{run_id}/stop").json()
        assert stopped["exit"] == "stopped" and stopped["recording_url"]
        pose = stopped["pose"]
        assert pose["x_mm"] == pytest.approx(200, abs=15)

        # The finished run's view sends the browser to its replay; scrubbed to the end, it draws.
        replay = context.new_page()
        replay.goto(view)
        assert "/replay/" in replay.url and "playbackPath=" in replay.url
        timeline = replay.locator(".mantine-Slider-root")  # viser's playback bar, once the file loaded
        timeline.wait_for(timeout=DRAW_TIMEOUT_S * 1000)
        box = timeline.bounding_box()
        replay.mouse.click(box["x"] + box["width"] - 1, box["y"] + box["height"] / 2)  # scrub to the end
        screenshot_when_drawn(replay, "replay-end.png")
    finally:
        context.close()

    # The replay's last frame is where the run ended: the robot's track ends at the final pose.
    recording = operator.get(stopped["recording_url"]).content
    track = robot_track(recording)
    assert len(track) > 30  # a frame for every drawn frame of a paced run
    moved_mm = (track[-1] - track[0]) * 1000
    assert moved_mm[0] == pytest.approx(pose["x_mm"], abs=2.0)
    assert moved_mm[1] == pytest.approx(pose["y_mm"], abs=2.0)
