"""A team's table on the Simulator page, in Debian's Chromium against a real `openbricks console`: the
world file and its mat picked as two files upload into the console's store, the new world is chosen
and listed, a run on it draws its 3D view and is listed with the world's name (on the page and in
the History), a bad world file shows its problems with their lines, and a viewer sees no upload."""

from __future__ import annotations

import pytest

from tests.sim.season_table import WORLD_TOML, write_table
from tests.web.conftest import screenshot

pytestmark = pytest.mark.e2e

RUN_S = 180_000
SHORT = """\
from openbricks.drivers.st3032 import ST3032Motor
from openbricks.robotics import DriveBase
from openbricks.tools import wait

left = ST3032Motor(servo_id=1, uart_id=1, tx=14, rx=41)
right = ST3032Motor(servo_id=2, uart_id=1, tx=14, rx=41, invert=True)
db = DriveBase(left, right, wheel_diameter_mm=88, axle_track_mm=138)
db.straight(100)
print('on the table')
wait(3000)
"""


def test_a_world_uploaded_on_the_page_runs_is_watched_and_listed_by_name(console, page_for, tmp_path):
    world = write_table(tmp_path)
    with console.api() as api:
        api.put("/api/programs/short.py", json={"source": SHORT}).raise_for_status()
    page = page_for(console.url)
    page.goto(f"{console.base}/#/sim")
    upload = page.locator("[data-testid=world-upload]")
    upload.locator("summary").click()

    bad = tmp_path / "bad"
    bad.mkdir()
    write_table(bad, WORLD_TOML.replace('mat = "mat.png"', 'mat = "gone.png"'))
    (bad / "mat.png").unlink()
    upload.get_by_label("World files").set_input_files([bad / "table.toml"])
    upload.get_by_role("button", name="Upload world").click()
    upload.get_by_role("alert").get_by_text("table.toml:3: mat: image 'gone.png' not found").wait_for()

    upload.get_by_label("World files").set_input_files([world, world.parent / "mat.png"])
    upload.get_by_role("button", name="Upload world").click()
    page.wait_for_function(
        "document.querySelector('select[aria-label=World]').value === 'season_table'", timeout=20000
    )
    assert upload.get_by_role("button", name="Upload world").is_disabled()  # the picker is empty again
    page.get_by_label("Program").select_option("short.py")
    page.get_by_role("button", name="Start simulation").click()
    page.frame_locator("iframe[title='3D view']").locator("canvas").first.wait_for(timeout=RUN_S)
    page.locator("[data-testid=sim-output]").get_by_text("on the table").wait_for(timeout=RUN_S)
    page.locator("[data-testid=sim-runs] tbody tr", has_text="season_table").first.wait_for(timeout=RUN_S)
    page.wait_for_timeout(1500)  # the view draws the table's mat
    screenshot(page, "sim-season-table")
    with console.api() as api:
        runs = api.get("/api/sim/runs").json()
    assert runs[0]["world"] == "season_table"
    page.goto(f"{console.base}/#/history?run={runs[0]['run_id']}")
    page.locator("[data-testid=sim-world]", has_text="season_table · seed").wait_for()
    assert not page.errors  # type: ignore[attr-defined]

    viewer = page_for(console.sign_in_url(console.mint("viewer"), "sim"))
    viewer.get_by_label("World").wait_for()
    assert viewer.locator("[data-testid=world-upload]").count() == 0
