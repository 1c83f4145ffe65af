"""The hubs API on a real daemon (uvicorn on 127.0.0.1) with real virtual hub processes: two hubs
running at once with their output kept apart on the event stream and in the history, 409 naming the
holder, stop-all, bad input refused with the error shape, and the history surviving a restart."""

from __future__ import annotations

import json
import time
from pathlib import Path

import pytest

from openbricks_server.daemon.config import DaemonConfig
from tests.server.daemon.conftest import Daemon

pytestmark = pytest.mark.e2e

COUNTING = (
    "from openbricks.tools import wait, plot\n"
    "for i in range(6):\n"
    "    print('{tag}', i)\n"
    "    plot('lap', i)\n"
    "    wait(30)\n"
)
ENDLESS = "from openbricks.tools import wait\nwhile True:\n    wait(50)\n"


def start_daemon(data_dir, virtual):
    return Daemon(DaemonConfig(host="127.0.0.1", port=0, virtual=virtual, ble=False, data_dir=data_dir))


def wait_idle(client, hubs, timeout_s=60):
    deadline = time.monotonic() + timeout_s
    while time.monotonic() < deadline:
        states = {h["name"]: h["status"] for h in client.get("/api/hubs").json()["hubs"]}
        if all(states.get(name) == "idle" for name in hubs):
            return
        time.sleep(0.1)
    raise AssertionError(f"hubs not idle: {states}")


def wait_ended(client, run_id, timeout_s=30):
    deadline = time.monotonic() + timeout_s
    while time.monotonic() < deadline:
        run = client.get(f"/api/runs/{run_id}").json()
        if run["outcome"] is not None:
            return run
        time.sleep(0.1)
    raise AssertionError(f"run {run_id} did not end")


@pytest.fixture
def daemon2(tmp_path, monkeypatch):
    monkeypatch.setenv("OPENBRICKS_DATA_DIR", str(tmp_path / "data"))
    running = start_daemon(tmp_path / "data", virtual=2)
    yield running
    running.stop()


def test_two_hubs_run_at_once_through_the_api_and_the_history_survives_a_restart(daemon2, tmp_path):
    with daemon2.client() as api, daemon2.websocket() as ws:
        wait_idle(api, ["SimHub-1", "SimHub-2"])
        listed = api.get("/api/hubs").json()
        assert [h["hub_id"] for h in listed["hubs"]] == ["virtual:SimHub-1", "virtual:SimHub-2"]
        assert listed["ble"] == "off (--no-ble)"
        a = api.post("/api/hubs/SimHub-1/run", json={"source": COUNTING.format(tag="A"), "name": "a.py"})
        b = api.post("/api/hubs/virtual:SimHub-2/run", json={"source": COUNTING.format(tag="B")})
        assert a.status_code == 200 and b.status_code == 200, (a.text, b.text)
        runs = {a.json()["run_id"]: "A", b.json()["run_id"]: "B"}
        seen: dict[str, list] = {run_id: [] for run_id in runs}
        ended = set()
        deadline = time.monotonic() + 30
        while ended != set(runs) and time.monotonic() < deadline:
            event = json.loads(ws.recv(timeout=10))
            if event["run"] in runs and event["type"] == "output":
                seen[event["run"]] += [(ln["line_no"], ln["text"]) for ln in event["data"]["lines"]]
            if event["run"] in runs and event["type"] == "run_ended":
                ended.add(event["run"])
        for run_id, tag in runs.items():
            assert seen[run_id][:6] == [(n + 1, f"{tag} {n}") for n in range(6)]
            detail = wait_ended(api, run_id)
            assert (detail["outcome"], detail["origin"], detail["who"]) == ("finished", "daemon", "local")
            assert "print('" + tag + "', i)" in detail["source"]
            samples = api.get(f"/api/runs/{run_id}/telemetry").json()
            assert [s["value"] for s in samples] == [0, 1, 2, 3, 4, 5]
        # the log read back after the run is the same run, not a second one, and stamps its lines
        wait_idle(api, ["SimHub-1", "SimHub-2"])
        assert {r["run_id"] for r in api.get("/api/runs").json()} == set(runs)
        for run_id in runs:
            lines = api.get(f"/api/runs/{run_id}/output").json()["lines"]
            started = api.get(f"/api/runs/{run_id}").json()["started_ms"]
            stamps = [ln["hub_ms"] for ln in lines]
            assert all(stamp and stamp >= started for stamp in stamps) and stamps == sorted(stamps)
    daemon2.stop()
    again = start_daemon(tmp_path / "data", virtual=0)
    try:
        with again.client() as api:
            kept = {r["run_id"]: r["outcome"] for r in api.get("/api/runs").json()}
            assert kept == {run_id: "finished" for run_id in runs}
            lines = api.get(f"/api/runs/{next(iter(runs))}/output").json()["lines"]
            assert [ln["text"] for ln in lines] == [f"A {n}" for n in range(6)]
    finally:
        again.stop()


def test_a_busy_hub_answers_409_naming_the_holder_and_stop_all_reaches_every_hub(daemon2):
    with daemon2.client() as api:
        wait_idle(api, ["SimHub-1", "SimHub-2"])
        first = api.post("/api/hubs/SimHub-1/run", json={"source": ENDLESS}).json()["run_id"]
        second = api.post("/api/hubs/SimHub-2/run", json={"source": ENDLESS}).json()["run_id"]
        refused = api.post("/api/hubs/SimHub-1/upload", json={"source": "print(1)\n"})
        assert refused.status_code == 409
        body = refused.json()
        assert body["error"] == "hub_busy" and "SimHub-1 is busy: run by local since" in body["message"]
        assert body["detail"]["holder"]["operation"] == "run" and body["hint"]
        stopped = api.post("/api/hubs/stop-all").json()["hubs"]
        assert [(r["name"], r["stopped"]) for r in stopped] == [("SimHub-1", True), ("SimHub-2", True)]
        assert all(r["detail"].startswith("stopped the program (run ") for r in stopped)
        assert all(r["detail"].endswith(", started by host run)") for r in stopped)
        assert wait_ended(api, first)["outcome"] == "stopped"
        assert wait_ended(api, second)["outcome"] == "stopped"


def test_bad_input_is_refused_with_the_error_shape_before_any_hub_is_touched(daemon2):
    with daemon2.client() as api:
        syntax = api.post("/api/hubs/SimHub-1/run", json={"source": "print('x'\n", "name": "bad.py"})
        assert syntax.status_code == 422 and "bad.py" in syntax.json()["message"]
        unknown = api.post("/api/hubs/NoSuchHub/run", json={"source": "print(1)\n"})
        assert unknown.status_code == 404 and unknown.json()["error"] == "hub_not_found"
        both = api.post("/api/hubs/SimHub-1/run", json={"source": "print(1)\n", "program": "x.py"})
        assert both.status_code == 422
        traversal = api.post("/api/hubs/SimHub-1/run", json={"program": "../etc/passwd"})
        assert traversal.status_code in (404, 422) and "error" in traversal.json()


def test_a_stored_program_runs_by_name_and_a_button_run_reaches_the_history(daemon2, tmp_path):
    from openbricks_server.link.discovery import control

    with daemon2.client() as api:
        wait_idle(api, ["SimHub-1"])
        saved = api.put("/api/programs/square.py", json={"source": "print('stored one')\n"})
        assert saved.status_code in (200, 201), saved.text
        run_id = api.post("/api/hubs/SimHub-1/run", json={"program": "square.py"}).json()["run_id"]
        detail = wait_ended(api, run_id)
        assert detail["program_name"] == "square.py" and detail["source"] == "print('stored one')\n"
        wait_idle(api, ["SimHub-1"])
        record = json.loads((tmp_path / "data" / "virtual-hubs" / "SimHub-1" / "endpoint.json").read_text())
        control(Path(record["control"]), {"op": "click"})  # the staged program, started by hand
        deadline = time.monotonic() + 30
        while time.monotonic() < deadline:
            by_hand = [r for r in api.get("/api/runs").json() if r["origin"] == "button"]
            if by_hand and by_hand[0]["outcome"]:
                break
            time.sleep(0.2)
        (run,) = by_hand
        assert run["outcome"] == "finished" and run["program_name"] == "square.py"
        lines = api.get(f"/api/runs/{run['run_id']}/output").json()["lines"]
        assert [ln["text"] for ln in lines] == ["stored one"]
        wait_idle(api, ["SimHub-1"])
        identified = api.post("/api/hubs/SimHub-1/identify", json={"duration_ms": 1000})
        assert identified.status_code == 200, identified.text
        assert identified.json()["identify_ms"] == 1000
        logs = api.get("/api/hubs/SimHub-1/logs").json()
        assert [entry["index"] for entry in logs] == [0, 1] and all(entry["bytes"] > 0 for entry in logs)
        read = api.get("/api/hubs/SimHub-1/logs/1").json()
        assert read["trigger"] == "button press" and read["outcome"] == "finished"
        assert [line["text"] for line in read["lines"]] == ["stored one"] and "-- run_1 --" in read["text"]
        gone = api.get("/api/hubs/SimHub-1/logs/7")
        assert gone.status_code == 404 and gone.json()["error"] == "log_not_found"


STAMPED = (
    "from openbricks.tools import wait, plot\n"
    "print('no newline yet', end='')\n"
    "wait(30)\n"
    "print(' ...now')\n"
    "for i in range(4):\n"
    "    print('line', i)\n"
    "    plot('lap', i)\n"
    "    wait(25)\n"
    "print('two\\nlines')\n"
    "raise ValueError('the end')\n"
)


def test_live_output_carries_the_hubs_stamp_and_history_shows_the_same(tmp_path, monkeypatch):
    monkeypatch.setenv("OPENBRICKS_DATA_DIR", str(tmp_path / "data"))
    daemon = start_daemon(tmp_path / "data", virtual=1)
    try:
        with daemon.client() as api, daemon.websocket() as ws:
            wait_idle(api, ["SimHub-1"])
            run_id = api.post("/api/hubs/SimHub-1/run", json={"source": STAMPED}).json()["run_id"]
            live: dict[int, tuple[str, int | None]] = {}
            samples = []
            deadline = time.monotonic() + 30
            while time.monotonic() < deadline:
                event = json.loads(ws.recv(timeout=10))
                if event["run"] != run_id:
                    continue
                if event["type"] == "output" and not event["data"].get("from_run_log"):
                    live.update({ln["line_no"]: (ln["text"], ln["hub_ms"]) for ln in event["data"]["lines"]})
                if event["type"] == "telemetry":
                    samples += [s["hub_ms"] for s in event["data"]["samples"]]
                if event["type"] == "run_ended":
                    break
            run = wait_ended(api, run_id)
            assert run["outcome"] == "error"
            wait_idle(api, ["SimHub-1"])
            (entry,) = api.get("/api/hubs/SimHub-1/logs").json()
            log = api.get(f"/api/hubs/SimHub-1/logs/{entry['index']}").json()
            assert log["started_ms"] == run["started_ms"]
            from_log = [(ln["text"], ln["hub_ms"]) for ln in log["lines"]]
            # every line has the hub's own stamp live, the one its run log has (the traceback's too)
            assert from_log[-1] == ("ValueError: the end", from_log[-1][1])
            assert [live[n] for n in sorted(live)] == from_log
            assert from_log[0] == ("no newline yet ...now", from_log[0][1]) and from_log[0][1] is not None
            assert all(hub_ms is not None and hub_ms >= run["started_ms"] for hub_ms in samples)
            assert len(samples) == 4
            history = api.get(f"/api/runs/{run_id}/output").json()["lines"]
            assert [(ln["text"], ln["hub_ms"]) for ln in history] == [live[n] for n in sorted(live)]
            stored = [s["hub_ms"] for s in api.get(f"/api/runs/{run_id}/telemetry").json()]
            assert stored == samples
    finally:
        daemon.stop()


def test_a_runtime_error_names_the_program_and_its_line_in_the_output_and_the_history(daemon2, tmp_path):
    """A virtual hub stages the source at /program.py; its traceback still names the program's own file,
    live and in the history, so the editor can mark the line, and so does a program-button run of it."""
    from openbricks_server.link.discovery import control

    with daemon2.client() as api:
        wait_idle(api, ["SimHub-1"])
        api.put("/api/programs/divide.py", json={"source": "print('a')\nx = 1\nprint(x / 0)\n"})
        run_id = api.post("/api/hubs/SimHub-1/run", json={"program": "divide.py"}).json()["run_id"]
        run = wait_ended(api, run_id)
        texts = [ln["text"] for ln in api.get(f"/api/runs/{run_id}/output").json()["lines"]]
        assert run["outcome"] == "error"
        assert '  File "divide.py", line 3, in <module>' in texts, texts
        assert not any("/program.py" in t for t in texts)

        wait_idle(api, ["SimHub-1"])
        record = json.loads((tmp_path / "data" / "virtual-hubs" / "SimHub-1" / "endpoint.json").read_text())
        control(Path(record["control"]), {"op": "click"})  # the staged program, started by hand
        deadline = time.monotonic() + 30
        while time.monotonic() < deadline:
            by_hand = [r for r in api.get("/api/runs").json() if r["origin"] == "button"]
            if by_hand and by_hand[0]["outcome"]:
                break
            time.sleep(0.2)
        (button,) = by_hand
        texts = [ln["text"] for ln in api.get(f"/api/runs/{button['run_id']}/output").json()["lines"]]
    assert button["outcome"] == "error"
    assert '  File "divide.py", line 3, in <module>' in texts, texts
