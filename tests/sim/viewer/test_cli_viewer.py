"""`openbricks sim run --viewer` and `openbricks sim preview` as a user meets them: the command prints
where to point the browser, the page is served on 127.0.0.1, the program's output still reaches the
terminal, and Ctrl-C ends the session cleanly."""

import re
import signal
import subprocess
import sys
import time
import urllib.request

import pytest

from .wire import WireClient

pytestmark = pytest.mark.e2e

PROGRAM = """\
import time
from openbricks.drivers.st3032 import ST3032Motor

left = ST3032Motor(1)
right = ST3032Motor(2, invert=True)
print("rolling")
left.run_speed(360)
right.run_speed(360)
time.sleep_ms(1000)
left.brake()
right.brake()
print("parked")
"""


def start(*args):
    return subprocess.Popen(
        [sys.executable, "-m", "openbricks_server.cli", "sim", *args],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )


def wait_for_url(process, timeout_s=60.0):
    """Read the command's stderr until it says where the 3D view is; returns the URL."""
    deadline = time.monotonic() + timeout_s
    seen = []
    while time.monotonic() < deadline:
        line = process.stderr.readline()
        if not line:
            break
        seen.append(line)
        found = re.search(r"3D view: (http://127\.0\.0\.1:\d+)", line)
        if found:
            return found.group(1)
    process.kill()
    raise AssertionError("no 3D view URL on stderr:\n" + "".join(seen))


def interrupt(process, timeout_s=15.0):
    """Ctrl-C, then the command's exit status and the rest of its output."""
    process.send_signal(signal.SIGINT)
    try:
        out, err = process.communicate(timeout=timeout_s)
    except subprocess.TimeoutExpired:
        process.kill()
        raise
    return process.returncode, out, err


def fetch(url):
    with urllib.request.urlopen(url, timeout=10) as response:
        return response.status, response.read()


def test_sim_run_viewer_serves_the_run_and_ends_on_ctrl_c(tmp_path):
    program = tmp_path / "roll.py"
    program.write_text(PROGRAM)
    process = start("run", str(program), "--viewer", "--speed", "2")
    try:
        url = wait_for_url(process)
        status, page = fetch(url)
        assert status == 200 and b"<html" in page.lower()
        with WireClient(int(url.rsplit(":", 1)[1])) as client:
            client.wait_for(lambda m: m.get("name") == "/bodies/robot/group0", what="the robot")
            client.wait_for(
                lambda m: str(m.get("updates", {}).get("_markdown", "")).startswith("**finished**"),
                timeout_s=30,
                what="the finished status",
            )
        code, out, err = interrupt(process)
    finally:
        if process.poll() is None:
            process.kill()
    assert code == 0, err
    assert out.splitlines()[:2] == ["rolling", "parked"]
    assert re.search(r"\[finished\] 1\.\d+ s simulated", err)


def test_sim_preview_shows_the_world_with_the_robot_until_ctrl_c():
    process = start("preview", "--world", "zones")
    try:
        url = wait_for_url(process)
        with WireClient(int(url.rsplit(":", 1)[1])) as client:
            client.wait_for(
                lambda m: m.get("name") == "/fixed_bodies/world/mat" and m["type"] == "GlbMessage"
            )
            # The robot stands at the world's start, 500 mm west of the mat centre.
            client.wait_for(
                lambda m: (
                    m.get("name") == "/bodies/robot/group0"
                    and "batched_positions" in m.get("updates", {})
                    and abs(m["updates"]["batched_positions"][0] + 0.5) < 0.002
                ),
                what="the robot at the start",
            )
            # A preview has no run to steer: no Pause button.
            assert not [m for _, m in client.messages("GuiButtonMessage") if m["props"]["label"] == "Pause"]
        code, _, err = interrupt(process)
    finally:
        if process.poll() is None:
            process.kill()
    assert code == 0, err


def test_a_hub_dir_that_cannot_be_a_flash_is_refused_before_the_viewer_starts(tmp_path):
    program = tmp_path / "roll.py"
    program.write_text(PROGRAM)
    not_a_dir = tmp_path / "flash"
    not_a_dir.write_text("a file")
    process = start("run", str(program), "--viewer", "--hub-dir", str(not_a_dir))
    out, err = process.communicate(timeout=60)
    assert process.returncode == 1
    assert f"hub directory {not_a_dir} is a file" in err and "3D view" not in err
    assert "Traceback" not in err and out == ""
