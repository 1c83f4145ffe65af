"""A team's world through the console's API, against a real daemon: uploaded as a zip of its world
file and mat, listed among the worlds and kept in the data folder; a run on it is scored by its
rules and shows the world's name in the history; a sweep over it draws a layout per seed; a bad
world file is refused with its lines; a viewer cannot upload."""

from __future__ import annotations

import io
import json
import zipfile

import pytest

from tests.sim.season_table import WORLD_TOML, write_table

from .test_sim import ended, save, start, wait_until

pytestmark = pytest.mark.e2e

PUSH = """\
from openbricks.drivers.st3032 import ST3032Motor
from openbricks.robotics import DriveBase
left = ST3032Motor(servo_id=1, uart_id=1, tx=14, rx=41)
right = ST3032Motor(servo_id=2, uart_id=1, tx=14, rx=41, invert=True)
db = DriveBase(left, right, wheel_diameter_mm=88, axle_track_mm=138)
db.settings(straight_speed=150)
db.straight(740)
"""


def season_zip(tmp_path, toml: str = WORLD_TOML) -> bytes:
    write_table(tmp_path, toml)
    buffer = io.BytesIO()
    with zipfile.ZipFile(buffer, "w") as archive:
        archive.write(tmp_path / "table.toml", "season/table.toml")
        archive.write(tmp_path / "mat.png", "season/mat.png")
    return buffer.getvalue()


def upload(client, data: bytes):
    return client.post("/api/sim/worlds", content=data, headers={"Content-Type": "application/zip"})


def test_an_uploaded_world_is_listed_kept_run_scored_and_swept(daemon, operator, tmp_path):
    answer = upload(operator, season_zip(tmp_path))
    assert answer.status_code == 201, answer.text
    assert answer.json()["name"] == "season_table" and answer.json()["props"] == 4
    worlds = operator.get("/api/sim/worlds").json()
    assert {"name": "season_table", "uploaded": True}.items() <= worlds[-1].items()
    assert "wro" in [w["name"] for w in worlds]
    kept = daemon.ctx.config.resolved_data_dir / "worlds" / "season_table"
    assert sorted(p.name for p in kept.iterdir()) == ["mat.png", "table.toml"]

    save(operator, "push.py", PUSH)
    # From the mat's lower-left (300, 1000) facing +x: the centre frame of a 2362 x 1143 mm mat.
    run = start(
        operator,
        program="push.py",
        world="season_table",
        speed=None,
        start={"x_mm": 300 - 1181, "y_mm": 1000 - 571.5, "heading_deg": 0},
    )
    done = wait_until(operator, run["run_id"], ended)
    assert done["exit"] == "finished", done["error"]
    assert done["world"] == "season_table"
    assert done["score"]["points"] == 25
    history = operator.get("/api/runs", params={"hub": "sim"}).json()
    listed = operator.get("/api/sim/runs").json()
    assert listed[0]["world"] == "season_table" and history

    job = operator.post(
        "/api/sim/sweeps", json={"program": "push.py", "world": "season_table", "seeds": "1-3", "workers": 2}
    ).json()
    swept = operator.get(f"/api/sim/sweeps/{job['job_id']}", params={"wait_s": 240}).json()
    assert swept["state"] == "done", swept["message"]
    layouts = {json.dumps(row["score"]["props"], sort_keys=True) for row in swept["result"]["rows"]}
    assert len(layouts) == 3
    assert swept["params"]["world"] == "season_table"  # a seed is run again by the world's name


def test_a_bad_world_is_refused_with_its_lines_and_a_viewer_cannot_upload(operator, viewer, tmp_path):
    bad = season_zip(tmp_path, WORLD_TOML.replace("size_mm = [2362, 1143]", "size_mm = [2362, 0]"))
    answer = upload(operator, bad)
    assert answer.status_code == 422
    assert answer.json()["detail"]["problems"] == ["table.toml:4: size_mm: must be positive, got 0"]
    assert upload(operator, b"not a zip").json()["error"] == "bad_world"
    assert upload(viewer, season_zip(tmp_path)).status_code == 403
    assert [w["name"] for w in operator.get("/api/sim/worlds").json() if w["uploaded"]] == []
    refused = operator.post("/api/sim/runs", json={"program": "x.py", "world": "nowhere"})
    assert refused.status_code == 422 and "POST /api/sim/worlds" in refused.json()["hint"]
