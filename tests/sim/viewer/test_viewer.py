"""The 3D view as a browser receives it: a client speaking viser's wire protocol connects to a SimViewer
on 127.0.0.1 while a program drives the simulated robot, and judges what arrives (the scene, the
robot's pose updates and their rate, the status and output panels) and what its button presses do.

Programs run on this (the main) thread, as `openbricks sim run --viewer` runs them."""

import threading
import time

import numpy as np
import pytest

from openbricks_sim.job import SimJob
from openbricks_sim.run import FINISHED, STOPPED, ProgramRun
from openbricks_sim.simulation import Simulation
from openbricks_sim.viewer import RemoteBindError, SimViewer, serve_run

from .wire import WireClient

ROBOT_NODE = "/bodies/robot/group0"

# Both wheels forward at 360 deg/s (~276 mm/s on 88 mm wheels) for `seconds`, then stop.
DRIVE = """\
import time
from openbricks.drivers.st3032 import ST3032Motor

left = ST3032Motor(1)
right = ST3032Motor(2, invert=True)
print("driving")
left.run_speed(360)
right.run_speed(360)
time.sleep_ms({ms})
left.brake()
right.brake()
print("stopped at", time.ticks_ms())
"""


def drive(seconds):
    return DRIVE.format(ms=round(seconds * 1000))


@pytest.fixture
def viewer():
    with SimViewer(port=0, speed=1.0) as v:
        yield v


@pytest.fixture
def page(viewer):
    with WireClient(viewer.port) as client:
        yield client


class RunStart:
    """The moment the run began (its world built and shown), and what a person does from then on.

    Building the world takes a moment that grows with the machine's load, so what the tests time
    and do is counted from here, not from when they asked for the run."""

    def __init__(self):
        self.at = None
        self._actions = []

    def after(self, seconds, action):
        self._actions.append((seconds, action))

    def elapsed(self):
        return time.perf_counter() - self.at

    def __call__(self):
        self.at = time.perf_counter()
        for seconds, action in self._actions:
            after(seconds, action)


def run_program(viewer, source, world="empty", speed=None, start=None):
    """Run source on this thread with the viewer attached; returns (result, simulation end pose).
    `start` (a RunStart) is told when the run begins."""
    sim = Simulation(world, "st3032", epoch_ms=0, speed=speed)
    try:
        run = ProgramRun(sim)
        viewer.attach(sim, stop=run.request_stop)
        if start is not None:
            start()
        result = None
        try:
            result = run.run(source, "mission.py", None, viewer.write)
        finally:
            viewer.detach(result)
        return result, sim.physics.pose()
    finally:
        sim.close()


def after(seconds, action):
    """Do action() on another thread `seconds` from now (a person reacting while the run goes on)."""
    timer = threading.Timer(seconds, action)
    timer.daemon = True
    timer.start()
    return timer


def robot_positions(page, since=0.0):
    """(arrival time, robot position in metres) of every robot pose update the page received."""
    return [
        (t, np.asarray(m["updates"]["batched_positions"], dtype=float).reshape(-1, 3)[0])
        for t, m in page.messages("SceneNodeUpdateMessage", since)
        if m["name"] == ROBOT_NODE and "batched_positions" in m["updates"]
    ]


def test_the_page_receives_the_world_the_robot_and_its_wheels(viewer, page):
    result, _ = run_program(viewer, "print('hello')\n", world="zones")
    assert result.exit == FINISHED
    robot = page.wait_for(
        lambda m: m.get("name") == ROBOT_NODE and m["type"] == "BatchedGlbMessage", what="robot"
    )
    assert len(np.asarray(robot["props"]["batched_positions"]).reshape(-1, 3)) == 1
    # Both wheels share one shape, so they travel as one batched node with two instances.
    wheels = page.wait_for(
        lambda m: m.get("name") == "/bodies/left_wheel/group0" and m["type"] == "BatchedGlbMessage",
        what="wheels",
    )
    assert len(np.asarray(wheels["props"]["batched_positions"]).reshape(-1, 3)) == 2
    # The printed mat arrives as a textured mesh (a glTF binary with an embedded image), not a grid.
    mat = page.wait_for(
        lambda m: m.get("name") == "/fixed_bodies/world/mat" and m["type"] == "GlbMessage", what="the mat"
    )
    glb = bytes(mat["props"]["glb_data"])
    assert glb[:4] == b"glTF" and b"image/png" in glb


def test_poses_stream_at_30_hz_or_more_and_follow_the_robot(viewer, page):
    start = RunStart()
    result, end = run_program(viewer, drive(2.5), start=start)
    assert result.exit == FINISHED, result.error
    # While the robot drives (the middle of the run, clear of start-up and the final stop).
    moving = robot_positions(page, since=start.at + 0.5)
    moving = [(t, p) for t, p in moving if t <= start.at + 2.3]
    arrivals = [t for t, _ in moving]
    rate_hz = (len(moving) - 1) / (arrivals[-1] - arrivals[0])
    assert rate_hz >= 30, f"{len(moving)} robot pose updates at {rate_hz:.1f} Hz"
    xs = [p[0] for _, p in moving]
    assert all(b >= a for a, b in zip(xs, xs[1:], strict=False)) and xs[-1] - xs[0] > 0.3
    # The last pose the page saw is where the physics left the robot.
    time.sleep(0.3)
    last = robot_positions(page)[-1][1]
    assert last[0] * 1000 == pytest.approx(end.x_mm, abs=2.0)
    assert last[1] * 1000 == pytest.approx(end.y_mm, abs=2.0)


def test_a_1x_run_takes_its_simulated_time_on_the_wall_clock(viewer):
    start = RunStart()
    result, _ = run_program(viewer, drive(1.5), start=start)
    assert result.exit == FINISHED
    assert start.elapsed() == pytest.approx(result.sim_ms / 1000, rel=0.15)


def test_pause_on_the_page_stops_simulated_time_until_resume(viewer, page):
    sim_ms = []
    start = RunStart()
    start.after(0.6, lambda: page.click("Pause"))
    start.after(1.0, lambda: sim_ms.append(viewer._frame.sim_ms))
    start.after(1.6, lambda: sim_ms.append(viewer._frame.sim_ms))
    start.after(1.7, lambda: page.click("Resume"))
    result, _ = run_program(viewer, drive(1.5), start=start)
    assert result.exit == FINISHED
    held_ms = sim_ms[1] - sim_ms[0]
    assert held_ms == 0, f"simulated time moved {held_ms} ms while paused"
    # About 1.1 s of pause on top of the 1.8 s run.
    assert start.elapsed() > result.sim_ms / 1000 + 0.8
    # The status line told the watcher so, and that the run went on afterwards.
    page.wait_for(
        lambda m: str(m.get("updates", {}).get("_markdown", "")).startswith("**finished**"),
        what="the finished status",
    )
    statuses = page.status_lines()
    paused_at = next(i for i, line in enumerate(statuses) if line.startswith("**paused**"))
    assert any(line.startswith("**running**") for line in statuses[paused_at:])
    assert statuses[-1].startswith("**finished**")


def test_the_speed_chosen_on_the_page_sets_the_pace(viewer, page):
    start = RunStart()
    start.after(0.3, lambda: page.choose("Speed", "4x"))
    result, _ = run_program(viewer, drive(4.0), start=start)
    wall_s = start.elapsed()
    # ~0.3 s at 1x, the remaining ~4 s at 4x: about 1.3 s, far from the 4.3 s of a 1x run.
    assert result.exit == FINISHED
    assert 1.0 < wall_s < 2.2, f"{result.sim_ms} ms took {wall_s:.2f} s"


def test_a_simulation_built_with_a_speed_hands_it_to_the_viewer(viewer, page):
    start = RunStart()
    result, _ = run_program(viewer, drive(1.5), speed=3.0, start=start)
    assert result.exit == FINISHED
    assert start.elapsed() == pytest.approx(result.sim_ms / 1000 / 3.0, abs=0.25)
    time.sleep(0.2)
    assert page.gui("Speed", "GuiDropdownMessage")["props"]["value"] == "3x"


def test_stop_on_the_page_ends_even_a_program_that_never_lets_time_pass(viewer, page):
    start = RunStart()
    start.after(0.8, lambda: page.click("Stop"))
    result, _ = run_program(viewer, "import time\ntime.sleep_ms(100)\nwhile True:\n    pass\n", start=start)
    assert result.exit == STOPPED
    assert start.elapsed() < 5.0


def test_program_output_reaches_the_page_as_text_never_as_markup(viewer, page):
    run_program(viewer, "print('<script>alert(1)</script> line one')\nprint('line two')\n")
    time.sleep(0.5)  # the output panel is redrawn a few times a second
    output = [m for _, m in page.messages() if m["type"] == "GuiHtmlMessage"][0]
    content = page.gui_content(output["uuid"])
    assert "&lt;script&gt;alert(1)&lt;/script&gt; line one\nline two" in content
    assert "<script>" not in content


def test_an_error_shows_its_traceback_in_the_output_panel(viewer, page):
    result, _ = run_program(viewer, "print('before')\nraise ValueError('bad mission')\n")
    assert result.exit == "error"
    time.sleep(0.5)
    output = [m for _, m in page.messages() if m["type"] == "GuiHtmlMessage"][0]
    content = page.gui_content(output["uuid"])
    assert "before" in content and "ValueError: bad mission" in content


def test_listening_beyond_this_machine_must_be_asked_for():
    with pytest.raises(RemoteBindError, match="no login"):
        SimViewer(host="0.0.0.0", port=0)


def test_a_taken_port_moves_the_viewer_to_the_next_one_and_its_url_says_so(viewer):
    with SimViewer(port=viewer.port) as second:
        assert second.port != viewer.port
        assert second.url == f"http://127.0.0.1:{second.port}"


def test_restart_on_the_page_runs_the_program_again_from_the_start():
    results = []
    urls = []
    clients = []

    def ready(url):
        urls.append(url)
        client = WireClient(int(url.rsplit(":", 1)[1]))
        clients.append(client)
        after(0.7, lambda: client.click("Restart"))

    try:
        final = serve_run(
            SimJob("mission.py", speed=2.0),
            source=drive(1.5),
            port=0,
            keep_open=False,
            on_ready=ready,
            on_result=results.append,
        )
    finally:
        for client in clients:
            client.close()
    # The first run was cut short (a stop lands when the program's sleep ends, and the rest of that
    # sleep is no longer paced); the second ran from the start to its end.
    assert [r.exit for r in results] == [STOPPED, FINISHED]
    assert results[0].wall_s < 1.0 and "stopped at" not in results[0].output
    assert results[1].output.startswith("driving") and "stopped at 15" in results[1].output
    assert final is results[1]
    assert final.job["viewer"] is True


def test_the_robots_oled_shows_in_the_panel_once_the_program_draws_on_it(viewer, page):
    source = (
        "from machine import I2C, Pin\n"
        "from openbricks.drivers.ssd1306 import SSD1306\n"
        "import time\n"
        "oled = SSD1306(I2C(0, sda=Pin(15), scl=Pin(16)))\n"
        "oled.fill_rect(0, 0, 8, 2, 1)\n"
        "oled.show()\n"
        "time.sleep_ms(500)\n"
    )
    run_program(viewer, source)
    time.sleep(0.5)
    contents = [page.gui_content(m["uuid"]) for _, m in page.messages() if m["type"] == "GuiHtmlMessage"]
    shown = [c for c in contents if "\u2588" in c]
    assert shown, "no OLED picture reached the page"
    assert "\u2588" * 8 + " " * 120 in shown[-1]  # the 8 x 2 block at the top-left, nothing else
