"""Competition mode on a real daemon (uvicorn on 127.0.0.1): the setting and its match timer are the
daemon's (every page sees them, a restart keeps them), and while the mode is on and a hub runs, the API
itself refuses uploads, new runs (hub, sim, sweep), flashing and servo re-ID with 409 and the reason,
whoever sends them, while stop and STOP ALL still work."""

from __future__ import annotations

import json
import time

import pytest

from tests.server.daemon.conftest import start_daemon
from tests.server.daemon.routers.test_hubs import ENDLESS, wait_ended, wait_idle
from tests.server.daemon.routers.test_hubs import start_daemon as start_daemon_with_hubs

HUBS = ["SimHub-1", "SimHub-2"]


def next_event(ws, type_: str, timeout_s: float = 10) -> dict:
    deadline = time.monotonic() + timeout_s
    while time.monotonic() < deadline:
        event = json.loads(ws.recv(timeout=timeout_s))
        if event["type"] == type_:
            return event
    raise AssertionError(f"no {type_} event")


def test_the_setting_is_the_daemons_announced_to_every_page_and_kept_across_a_restart(tmp_path):
    daemon = start_daemon(tmp_path / "data")
    try:
        viewer_token = daemon.ctx.store.tokens.mint("viewer", "judge")
        with daemon.client() as api, daemon.client(viewer_token) as judge, daemon.websocket() as ws:
            first = api.get("/api/competition").json()
            assert (first["on"], first["match_s"], first["match_started_ms"], first["locked"]) == (
                False,
                150,
                None,
                False,
            )
            refused = api.post("/api/competition/match/start")
            assert refused.status_code == 409 and refused.json()["error"] == "competition_off"
            assert "PUT /api/competition" in refused.json()["hint"]

            on = api.put("/api/competition", json={"on": True, "match_s": 120}).json()
            assert (on["on"], on["match_s"], on["changed_by"]) == (True, 120, "local")
            announced = next_event(ws, "competition")["data"]
            assert (announced["on"], announced["match_s"]) == (True, 120)

            started = api.post("/api/competition/match/start").json()
            assert abs(started["match_started_ms"] - started["server_ms"]) < 5000
            # A viewer (a judge's page) sees the same timer but cannot touch it.
            seen = judge.get("/api/competition").json()
            assert seen["match_started_ms"] == started["match_started_ms"]
            denied = judge.put("/api/competition", json={"on": False})
            assert denied.status_code == 403 and denied.json()["error"] == "operator_required"

            bad = api.put("/api/competition", json={"match_s": 5})
            assert bad.status_code == 422 and bad.json()["detail"]["field"] == "match_s"
    finally:
        daemon.stop()

    again = start_daemon(tmp_path / "data")
    try:
        with again.client() as api:
            kept = api.get("/api/competition").json()
            assert (kept["on"], kept["match_s"], kept["match_started_ms"]) == (
                True,
                120,
                started["match_started_ms"],
            )
            off = api.put("/api/competition", json={"on": False}).json()
            assert (off["on"], off["match_started_ms"]) == (False, None)  # off also resets the timer
    finally:
        again.stop()


@pytest.mark.e2e
def test_while_a_hub_runs_uploads_and_new_runs_are_refused_by_the_api_and_stop_still_works(tmp_path):
    daemon = start_daemon_with_hubs(tmp_path / "data", virtual=2)
    try:
        viewer_token = daemon.ctx.store.tokens.mint("viewer", "mentor")
        with daemon.client() as api, daemon.client(viewer_token) as mentor, daemon.websocket() as ws:
            wait_idle(api, HUBS)
            api.put("/api/programs/square.py", json={"source": "print('square')\n"}).raise_for_status()
            api.put("/api/competition", json={"on": True}).raise_for_status()
            # Nothing runs yet: the mode alone locks nothing.
            first = api.post("/api/hubs/SimHub-1/run", json={"source": ENDLESS, "name": "endless.py"})
            assert first.status_code == 200, first.text
            run_id = first.json()["run_id"]

            state = api.get("/api/competition").json()
            assert (state["locked"], state["running"]) == (True, ["SimHub-1"])
            attempts = {
                "upload a program on SimHub-2": api.post(
                    "/api/hubs/SimHub-2/upload", json={"program": "square.py"}
                ),
                "start a run on SimHub-2": api.post("/api/hubs/SimHub-2/run", json={"program": "square.py"}),
                "upload a program on SimHub-1": api.post(
                    "/api/hubs/SimHub-1/upload", json={"source": "print(1)\n"}
                ),
                "start a sim run": api.post("/api/sim/runs", json={"program": "square.py"}),
                "start a sweep": api.post("/api/sim/sweeps", json={"program": "square.py", "seeds": "1-3"}),
                "flash firmware": api.post(
                    "/api/flash", json={"targets": [{"port": "/dev/ttyUSB9", "name": "B"}]}
                ),
                "change a servo's id": api.post(
                    "/api/servos/set-id", json={"port": "/dev/ttyUSB9", "new_id": 3}
                ),
            }
            for what, reply in attempts.items():
                body = reply.json()
                assert reply.status_code == 409 and body["error"] == "competition_locked", (what, body)
                assert body["message"].startswith(f"cannot {what}: competition mode locks uploads")
                assert body["message"].endswith("SimHub-1 is running"), body["message"]
                assert "stop" in body["hint"] and body["detail"]["running"] == ["SimHub-1"]
            assert api.get("/api/sim/runs").json() == []  # nothing was started behind the refusal
            assert api.get("/api/sim/sweeps").json() == []
            assert api.get("/api/jobs").json() == []  # no flash or servo job either
            # A viewer is told about the role, not the lock.
            assert mentor.post("/api/hubs/SimHub-2/upload", json={"program": "square.py"}).status_code == 403
            audited = [(e["action"], e["status"]) for e in api.get("/api/system/audit").json()]
            assert ("POST /api/hubs/SimHub-2/upload", 409) in audited

            # Stopping is never locked, over the event stream's WebSocket either.
            ws.send(json.dumps({"cmd": "stop_all", "id": 1}))
            reply = next_event(ws, "reply", timeout_s=30)["data"]
            assert reply["ok"], reply
            stopped = {r["name"]: r["stopped"] for r in reply["result"]["hubs"]}
            assert stopped == {"SimHub-1": True, "SimHub-2": False}
            assert wait_ended(api, run_id)["outcome"] == "stopped"
            wait_idle(api, HUBS)
            assert api.get("/api/competition").json()["locked"] is False
            uploaded = api.post("/api/hubs/SimHub-2/upload", json={"program": "square.py"})
            assert uploaded.status_code == 200, uploaded.text
    finally:
        daemon.stop()
