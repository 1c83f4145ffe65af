"""Sim runs through the console's API, against a real daemon that starts real simulator processes:
a run ends in the history with world, seed, result and recording; pause, resume, speed and stop steer
it; bad input is refused with a reason; a program that loops forever, eats memory or forks ends as
that run's outcome while the daemon and another run go on."""

from __future__ import annotations

import json
import os
import threading
import time

import pytest

STRAIGHT = """\
from openbricks.drivers.st3032 import ST3032Motor
from openbricks.robotics import DriveBase

left = ST3032Motor(servo_id=1, uart_id=1, tx=14, rx=41)
right = ST3032Motor(servo_id=2, uart_id=1, tx=14, rx=41, invert=True)
db = DriveBase(left, right, wheel_diameter_mm=88, axle_track_mm=138)
print("driving")
db.straight(200)
db.stop(then="brake")
print("done")
"""
TICKER = """\
import time
n = 0
while True:
    n += 1
    print("tick", n)
    time.sleep_ms(100)
"""
FOREVER = "while True:\n    pass\n"
HOG = "chunks = []\nwhile True:\n    chunks.append(bytearray(8 * 1024 * 1024))\n"
FORK = "import os\nprint('forking')\nos.fork()\nprint('forked')\n"

END_TIMEOUT_S = 120


def save(client, name: str, source: str) -> None:
    assert client.put(f"/api/programs/{name}", json={"source": source}).status_code in (200, 201)


def start(client, **body) -> dict:
    answer = client.post("/api/sim/runs", json=body)
    assert answer.status_code == 201, answer.text
    return answer.json()


def wait_until(client, run_id: str, predicate, timeout_s: float = END_TIMEOUT_S) -> dict:
    deadline = time.monotonic() + timeout_s
    while True:
        run = client.get(f"/api/sim/runs/{run_id}").json()
        if predicate(run):
            return run
        assert time.monotonic() < deadline, f"sim run never got there: {run}"
        time.sleep(0.2)


def ended(run: dict) -> bool:
    return not run["live"]


def running(run: dict) -> bool:
    return run["state"] == "running" or not run["live"]


class EventLog:
    """The event stream, collected on a thread."""

    def __init__(self, daemon):
        self.events: list[dict] = []
        self.ws = daemon.websocket()
        self.thread = threading.Thread(target=self._read, daemon=True)
        self.thread.start()

    def _read(self):
        try:
            for message in self.ws:
                self.events.append(json.loads(message))
        except Exception:  # noqa: BLE001 - closed at the end of the test
            pass

    def of(self, run_id: str, type_: str) -> list[dict]:
        return [e for e in self.events if e["run"] == run_id and e["type"] == type_]

    def close(self):
        self.ws.close()


@pytest.mark.e2e
def test_a_sim_run_streams_its_output_and_telemetry_and_lands_in_the_history(daemon, operator):
    save(operator, "straight.py", STRAIGHT)
    events = EventLog(daemon)
    try:
        run = start(operator, program="straight.py", world="zones", seed=7, speed=None)
        assert run["state"] == "queued" and run["kind"] == "sim" and run["job_id"] == run["run_id"]
        run = wait_until(operator, run["run_id"], ended)
        time.sleep(0.3)  # the last events are on their way
    finally:
        events.close()
    run_id = run["run_id"]
    assert run["state"] == "done" and run["exit"] == "finished", run
    assert run["world"] == "zones" and run["seed"] == 7 and run["chassis"] == "st3032"
    assert run["score"] is not None  # the zones world scores its final state
    assert run["pose"]["x_mm"] > run["start_mm_deg"][0] + 150 if run["start_mm_deg"] else run["pose"]
    assert run["progress"] == 100.0 and run["replay_url"] and run["recording_url"]

    history = operator.get("/api/runs", params={"origin": "sim"}).json()
    assert [r["run_id"] for r in history] == [run_id]
    assert history[0]["hub_id"] == "sim" and history[0]["outcome"] == "finished"
    lines = [ln["text"] for ln in operator.get(f"/api/runs/{run_id}/output").json()["lines"]]
    assert lines == ["driving", "done"]
    names = {s["name"] for s in operator.get(f"/api/runs/{run_id}/telemetry").json()}
    assert names == {"x_mm", "y_mm", "heading_deg", "left_dps", "right_dps"}
    speeds = operator.get(f"/api/runs/{run_id}/telemetry", params={"name": "left_dps"}).json()
    assert max(s["value"] for s in speeds) > 100  # the wheels turned

    states = [e["data"]["job"]["state"] for e in events.of(run_id, "job")]
    assert states[0] == "queued" and "running" in states and states[-1] == "done"
    streamed = [ln["text"] for e in events.of(run_id, "output") for ln in e["data"]["lines"]]
    assert streamed == ["driving", "done"]
    assert events.of(run_id, "telemetry") and events.of(run_id, "run_ended")

    recording = operator.get(f"/api/sim/runs/{run_id}/recording")
    assert recording.status_code == 200 and len(recording.content) > 1000
    assert f'filename="{run_id}.viser"' in recording.headers["content-disposition"]
    listed = operator.get("/api/sim/runs").json()
    assert [r["run_id"] for r in listed] == [run_id]


@pytest.mark.e2e
def test_pause_resume_speed_and_stop_steer_a_live_run(daemon, operator):
    save(operator, "ticker.py", TICKER)
    run = start(operator, program="ticker.py", speed=1.0, limit_ms=600_000)
    run_id = run["run_id"]
    wait_until(operator, run_id, lambda r: r["state"] == "running" and r["sim_ms"] > 0)
    job = daemon.ctx.sim.live[run_id]

    paused = operator.post(f"/api/sim/runs/{run_id}/pause").json()
    assert paused["paused"] is True
    time.sleep(0.5)
    held = operator.get(f"/api/sim/runs/{run_id}").json()["sim_ms"]
    time.sleep(1.0)
    assert operator.get(f"/api/sim/runs/{run_id}").json()["sim_ms"] == held  # simulated time stands still

    assert operator.post(f"/api/sim/runs/{run_id}/resume").json()["paused"] is False
    faster = operator.post(f"/api/sim/runs/{run_id}/speed", json={"speed": 4}).json()
    assert faster["speed"] == 4.0
    before = operator.get(f"/api/sim/runs/{run_id}").json()["sim_ms"]
    time.sleep(1.0)
    gained = operator.get(f"/api/sim/runs/{run_id}").json()["sim_ms"] - before
    assert gained > 1500, gained  # about 4 s of simulated time a second (a loaded machine does less)

    stopped = operator.post(f"/api/sim/runs/{run_id}/stop")
    assert stopped.status_code == 200
    run = stopped.json()
    assert run["state"] == "cancelled" and run["exit"] == "stopped" and not run["live"]
    assert job._process.returncode is not None  # its process is gone
    with pytest.raises(ProcessLookupError):
        os.kill(job._process.pid, 0)
    again = operator.post(f"/api/sim/runs/{run_id}/pause")
    assert again.status_code == 409 and again.json()["error"] == "sim_run_ended"
    assert operator.get("/api/runs", params={"origin": "sim"}).json()[0]["outcome"] == "stopped"


def test_bad_input_is_refused_with_a_reason(daemon, operator):
    save(operator, "ticker.py", TICKER)
    cases = [
        ({"program": "ticker.py", "world": "moon"}, 422, "unknown_world"),
        ({"program": "ticker.py", "chassis": "tank"}, 422, "invalid_request"),
        ({"program": "ticker.py", "seed": -1}, 422, "invalid_request"),
        ({"program": "ticker.py", "speed": 0}, 422, "invalid_request"),
        ({"program": "ticker.py", "limit_ms": 0}, 422, "invalid_request"),
        ({"program": "nothere.py"}, 404, "not_found"),
        ({"program": "../etc/passwd"}, 422, None),
    ]
    for body, status, error in cases:
        answer = operator.post("/api/sim/runs", json=body)
        assert answer.status_code == status, (body, answer.text)
        problem = answer.json()
        assert problem["message"] and (error is None or problem["error"] == error), problem
    assert "moon" in operator.post("/api/sim/runs", json=cases[0][0]).json()["message"]
    assert "seed" in operator.post("/api/sim/runs", json=cases[2][0]).json()["message"]
    unknown = operator.get("/api/sim/runs/01ARZ3NDEKTSV4RRFFQ69G5FAV")
    assert unknown.status_code == 404 and unknown.json()["error"] == "not_found"
    assert operator.get("/api/sim/runs/nope").json()["error"] == "bad_run_id"
    assert operator.get("/api/sim/runs").json() == []  # nothing was started


def test_a_viewer_may_watch_but_not_start_or_stop(daemon, operator, viewer):
    save(operator, "ticker.py", TICKER)
    refused = viewer.post("/api/sim/runs", json={"program": "ticker.py"})
    assert refused.status_code == 403 and refused.json()["error"] == "operator_required"
    refused = viewer.post("/api/sim/runs/01ARZ3NDEKTSV4RRFFQ69G5FAV/stop")
    assert refused.status_code == 403
    assert viewer.get("/api/sim/runs").status_code == 200
    assert [w["name"] for w in viewer.get("/api/sim/worlds").json()][:1] == ["empty"]


@pytest.mark.e2e
def test_runaway_programs_end_as_their_runs_outcome_and_the_daemon_goes_on(daemon, operator):
    for name, source in (
        ("forever.py", FOREVER),
        ("hog.py", HOG),
        ("fork.py", FORK),
        ("straight.py", STRAIGHT),
    ):
        save(operator, name, source)
    forever = start(operator, program="forever.py", speed=None, wall_limit_s=4)
    hog = start(operator, program="hog.py", speed=None, memory_mb=512)
    fork = start(operator, program="fork.py", speed=None)
    good = start(operator, program="straight.py", speed=None)
    busy = operator.post("/api/sim/runs", json={"program": "straight.py"})
    assert busy.status_code == 409 and busy.json()["error"] == "sim_busy"  # four at once at most

    started = time.monotonic()
    while time.monotonic() - started < 3:  # the daemon answers at once while they run
        t0 = time.monotonic()
        assert operator.get("/api/system/health").status_code == 200
        assert time.monotonic() - t0 < 1.0
        time.sleep(0.2)

    forever = wait_until(operator, forever["run_id"], ended)
    assert forever["exit"] == "wall_limit" and forever["state"] == "failed"
    assert "wall-clock limit" in forever["error"] and "sleep" in forever["error"]
    hog = wait_until(operator, hog["run_id"], ended)
    assert hog["exit"] == "memory_limit" and "memory limit" in hog["error"], hog
    fork = wait_until(operator, fork["run_id"], ended)
    assert fork["exit"] == "error" and fork["state"] == "failed"
    assert "fork" in fork["error"], fork["error"]
    good = wait_until(operator, good["run_id"], ended)
    assert good["exit"] == "finished" and good["state"] == "done"
    outcomes = {
        r["program_name"]: r["outcome"] for r in operator.get("/api/runs", params={"origin": "sim"}).json()
    }
    assert outcomes == {
        "forever.py": "wall_limit",
        "hog.py": "memory_limit",
        "fork.py": "error",
        "straight.py": "finished",
    }


@pytest.mark.e2e
def test_a_daemon_that_shuts_down_stops_its_live_runs_and_records_them(tmp_path):
    from openbricks_server.daemon.store import Store

    from ..conftest import start_daemon

    daemon = start_daemon(tmp_path / "data")
    try:
        with daemon.client() as client:
            save(client, "ticker.py", TICKER)
            run = start(client, program="ticker.py", speed=1.0, limit_ms=600_000)
            wait_until(client, run["run_id"], lambda r: r["state"] == "running" and r["sim_ms"] > 0)
            process = daemon.ctx.sim.live[run["run_id"]]._process
    finally:
        daemon.stop()
    with pytest.raises(ProcessLookupError):
        os.kill(process.pid, 0)
    store = Store(daemon.config.db_path)
    try:
        row = store.sim_runs.get(run["run_id"])
        assert row["state"] == "cancelled" and row["exit"] == "stopped" and row["recording"]
        assert store.runs.get(run["run_id"])["outcome"] == "stopped"
    finally:
        store.close()
