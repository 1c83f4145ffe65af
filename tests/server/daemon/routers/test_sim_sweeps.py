"""Seed sweeps through the console's API, against a real daemon whose seeds run in real simulator
child processes: the rows match the CLI's engine run directly, progress is a step per seed, the CSV is
the command's, and bad input is refused before any seed runs."""

from __future__ import annotations

import csv
import io

import pytest

from openbricks_sim.job import SimJob
from openbricks_sim.sweep import sweep

from .test_sim import STRAIGHT, save

pytestmark = pytest.mark.e2e

WAIT_S = 240


def comparable(row: dict) -> dict:
    return {key: value for key, value in row.items() if key != "wall_s"}


def test_a_sweep_runs_every_seed_and_gives_the_rows_the_cli_engine_gives(daemon, operator):
    save(operator, "straight.py", STRAIGHT)
    answer = operator.post(
        "/api/sim/sweeps", json={"program": "straight.py", "world": "zones", "seeds": "1-3", "workers": 2}
    )
    assert answer.status_code == 202, answer.text
    job = answer.json()
    assert job["kind"] == "sim_sweep" and job["params"]["seeds"] == [1, 2, 3]
    assert job["params"]["version"] == operator.get("/api/programs/straight.py").json()["version"]
    done = operator.get(f"/api/sim/sweeps/{job['job_id']}", params={"wait_s": WAIT_S}).json()
    assert done["state"] == "done", done["message"]
    assert done["progress"] == 100.0 and len(done["steps"]) == 3
    rows = done["result"]["rows"]
    assert [row["seed"] for row in rows] == [1, 2, 3]
    assert {row["exit"] for row in rows} == {"finished"}
    assert done["result"]["summary"]["success_rate"] == 1.0

    direct = sorted(
        (row.summary() for row in sweep(SimJob("straight.py", world="zones"), [1, 2, 3], 2, source=STRAIGHT)),
        key=lambda row: row["seed"],
    )
    assert [comparable(row) for row in rows] == [comparable(row) for row in direct]

    exported = operator.get(f"/api/sim/sweeps/{job['job_id']}/rows.csv")
    assert exported.status_code == 200 and exported.headers["content-type"].startswith("text/csv")
    table = list(csv.DictReader(io.StringIO(exported.text)))
    assert [line["seed"] for line in table] == ["1", "2", "3"] and {line["exit"] for line in table} == {
        "finished"
    }
    assert [j["job_id"] for j in operator.get("/api/sim/sweeps").json()] == [job["job_id"]]


def test_bad_sweeps_are_refused_before_any_seed_runs(daemon, operator):
    save(operator, "straight.py", STRAIGHT)

    def refused(status, code, **body):
        answer = operator.post("/api/sim/sweeps", json={"program": "straight.py", "seeds": "1-2", **body})
        assert answer.status_code == status, answer.text
        assert answer.json()["error"] == code
        return answer.json()["message"]

    assert "runs backwards; write 1-5" in refused(422, "bad_seeds", seeds="5-1")
    assert "not a seed or a range" in refused(422, "bad_seeds", seeds="one")
    assert "unknown world 'moon'" in refused(422, "unknown_world", world="moon")
    assert "not both" in refused(422, "bad_sweep", workers=2, dask="tcp://127.0.0.1:8786")
    refused(404, "not_found", program="missing.py")
    assert operator.get("/api/sim/sweeps").json() == []


def test_a_dask_scheduler_that_is_not_there_fails_the_sweep_with_the_reason(daemon, operator):
    save(operator, "straight.py", STRAIGHT)
    job = operator.post(
        "/api/sim/sweeps", json={"program": "straight.py", "seeds": "1", "dask": "tcp://127.0.0.1:9"}
    ).json()
    done = operator.get(f"/api/sim/sweeps/{job['job_id']}", params={"wait_s": 60}).json()
    assert done["state"] == "failed"
    assert "cannot reach the Dask scheduler at tcp://127.0.0.1:9" in done["message"]
    csv_answer = operator.get(f"/api/sim/sweeps/{job['job_id']}/rows.csv")
    assert csv_answer.status_code == 409 and "has no rows" in csv_answer.json()["message"]
