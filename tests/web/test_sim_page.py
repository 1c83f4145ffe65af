"""The Simulator page in Debian's Chromium against a real `openbricks console`: a stored program started
from the page runs in a simulator child process, its 3D view (viser, through the console's port) draws
in the page with the run's output and telemetry beside it, the finished run turns into its replay (also
when opened later from the page's list of runs), and a sweep started from the page reports every seed;
a viewer can start nothing."""

from __future__ import annotations

import pytest

from tests.web.conftest import screenshot

pytestmark = pytest.mark.e2e

DRIVE = """\
from openbricks.drivers.st3032 import ST3032Motor
from openbricks.robotics import DriveBase
from openbricks.tools import plot

left = ST3032Motor(servo_id=1, uart_id=1, tx=14, rx=41)
right = ST3032Motor(servo_id=2, uart_id=1, tx=14, rx=41, invert=True)
db = DriveBase(left, right, wheel_diameter_mm=88, axle_track_mm=138)
print("driving")
plot("target_mm", 150)
db.straight(150)
plot("target_mm", 0)
print("arrived")
"""
RUN_S = 180_000  # a simulator child starts in seconds here, more on a loaded machine


def test_a_run_started_on_the_page_draws_its_view_then_replays_and_a_sweep_reports_each_seed(
    console, page_for
):
    with console.api() as api:
        api.put("/api/programs/drive.py", json={"source": DRIVE}).raise_for_status()
    page = page_for(console.url)
    page.goto(f"{console.base}/#/sim")
    page.get_by_label("Program").select_option("drive.py")
    page.get_by_label("World", exact=True).select_option("empty")
    page.get_by_role("button", name="Start simulation").click()

    view = page.frame_locator("iframe[title='3D view']")
    view.locator("canvas").first.wait_for(timeout=RUN_S)
    # Beside the view: the run's output, and its pose and wheel speeds plotted as they come.
    output = page.locator("[data-testid=sim-output]")
    output.get_by_text("driving").wait_for(timeout=RUN_S)
    page.locator("[data-testid=sim-telemetry] canvas").first.wait_for(timeout=RUN_S)
    page.get_by_role("link", name="Replay").wait_for(timeout=RUN_S)  # the run ended
    assert "done" in page.locator(".runbar").inner_text()
    output.get_by_text("arrived").wait_for()
    page.frame_locator("iframe[title='3D view']").locator("canvas").first.wait_for(timeout=RUN_S)
    screenshot(page, "sim-replay")
    with console.api() as api:
        (run,) = api.get("/api/sim/runs").json()
    assert run["exit"] == "finished" and run["program_name"] == "drive.py"
    # plot() in the simulator as on a hub: samples in the run's telemetry, nothing in its output.
    with console.api() as api:
        samples = api.get(f"/api/runs/{run['run_id']}/telemetry").json()
        lines = api.get(f"/api/runs/{run['run_id']}/output").json()["lines"]
    assert [s["value"] for s in samples if s["name"] == "target_mm"] == [150, 0]
    assert [line["text"] for line in lines] == ["driving", "arrived"], lines

    # A past run, opened from the list on a fresh page: its replay, with its stored output and telemetry.
    again = page_for(console.sign_in_url(console.token, "sim"))
    again.locator("[data-testid=sim-runs] tbody tr", has_text="drive.py").click()
    again.frame_locator("iframe[title='3D view']").locator("canvas").first.wait_for(timeout=RUN_S)
    again.get_by_role("link", name="Replay").wait_for()
    again.locator("[data-testid=sim-output]").get_by_text("arrived").wait_for()
    again.locator("[data-testid=sim-telemetry] .u-legend", has_text="x_mm").wait_for()
    again.locator("[data-testid=sim-telemetry]", has_text="target_mm").first.wait_for()
    # The same run from the History: its 3D replay, and run again (in the simulator, not on a hub).
    again.goto(f"{console.base}/#/history?run={run['run_id']}")
    again.get_by_role("button", name="3D replay").click()
    again.wait_for_url(f"**/#/sim?run={run['run_id']}")
    again.get_by_role("link", name="Replay").wait_for()
    again.goto(f"{console.base}/#/history?run={run['run_id']}")
    again.get_by_role("button", name="Run again").click()
    again.wait_for_url("**/#/sim?run=*")
    assert run["run_id"] not in again.url
    again.locator("[data-testid=sim-output]").get_by_text("arrived").wait_for(timeout=RUN_S)
    assert again.errors == [], again.errors

    page.fill("input[placeholder='1-50']", "1-2")
    page.get_by_role("button", name="Start sweep").click()
    row = page.locator(".sweeps tbody tr").first
    row.wait_for(timeout=RUN_S)
    page.locator(".sweeps tbody tr", has_text="done").wait_for(timeout=RUN_S)
    assert "100 %" in row.inner_text()
    # The sweep's seeds, a row each.
    seeds = page.locator("[data-testid=sweep-rows] tbody tr")
    seeds.nth(1).wait_for()
    assert [seeds.nth(i).locator("td").first.inner_text() for i in range(seeds.count())] == ["1", "2"]
    seeds.nth(1).scroll_into_view_if_needed()
    screenshot(page, "sim-sweep")
    # A seed is run again, as the sweep ran it, to watch.
    seeds.nth(1).get_by_role("button", name="Watch").click()
    page.wait_for_url("**/#/sim?run=*")
    page.locator("[data-testid=sim-output]").get_by_text("arrived").wait_for(timeout=RUN_S)
    with console.api() as api:
        watched = api.get("/api/sim/runs").json()[0]
    assert (watched["seed"], watched["program_name"]) == (2, "drive.py")

    # Run from the editor with the simulator as its target: the Simulator page opens on that run.
    page.goto(f"{console.base}/#/editor")
    page.locator("button.prog", has_text="drive.py").click()
    page.locator("label.target", has_text="Simulator").locator("input").check()
    page.click("[data-testid=run]")
    page.wait_for_url("**/#/sim?run=*")
    page.locator("[data-testid=sim-output]").get_by_text("arrived").wait_for(timeout=RUN_S)
    assert page.errors == [], page.errors

    viewer = page_for(console.sign_in_url(console.mint("viewer"), "sim"))
    assert viewer.get_by_role("button", name="Start simulation").is_disabled()
    assert viewer.get_by_role("button", name="Start sweep").is_disabled()
