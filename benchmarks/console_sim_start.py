"""How soon a console sim run shows its first output: POST /api/sim/runs to the program's first line.

A real daemon (uvicorn on 127.0.0.1, in this process, no hubs) starts a run of a program whose first
line prints and whose second drives, and the output of the run is read back through the API (every
2 ms) until that line is there: what a browser waiting on the Run button sees, the child's start
included. The run's children come from the daemon's warm fork server (server/daemon/sim/warm.py);
for comparison the same is measured with every child spawned cold, a new interpreter importing
MuJoCo and the 3D view itself, as before the fork server (and as the daemon's first sim run still
is: it starts the fork server). ROUNDS runs each, alternating, after a run that waits for the fork
server's own imports; medians kept.
"""

from __future__ import annotations

import statistics
import tempfile
import time
from pathlib import Path

import httpx

from benchmarks import Row
from benchmarks.console_sim_view import _Daemon

ROUNDS = 7
POLL_S = 0.002
PROGRAM = """\
print("hello from the sim")
from openbricks.drivers.st3032 import ST3032Motor
from openbricks.robotics import DriveBase

left = ST3032Motor(servo_id=1, uart_id=1, tx=14, rx=41)
right = ST3032Motor(servo_id=2, uart_id=1, tx=14, rx=41, invert=True)
DriveBase(left, right, wheel_diameter_mm=88, axle_track_mm=138).straight(100)
"""


def _first_output_s(client: httpx.Client) -> float:
    """Seconds from the POST to the run's first output line in the API; the run is then left to end."""
    posted = time.perf_counter()
    run = client.post("/api/sim/runs", json={"program": "start.py", "speed": None, "limit_ms": 10_000})
    run.raise_for_status()
    run_id = run.json()["run_id"]
    while True:
        lines = client.get(f"/api/runs/{run_id}/output").json()["lines"]
        if lines:
            took = time.perf_counter() - posted
            break
        if time.perf_counter() - posted > 60:
            raise RuntimeError(f"sim run {run_id} showed no output within 60 s")
        time.sleep(POLL_S)
    while client.get(f"/api/sim/runs/{run_id}").json()["live"]:
        time.sleep(0.05)
    return took


def run() -> list[Row]:
    with tempfile.TemporaryDirectory() as tmp:
        daemon = _Daemon(Path(tmp) / "data")
        try:
            headers = {"Authorization": f"Bearer {daemon.token}"}
            with httpx.Client(base_url=daemon.url, headers=headers, timeout=60) as client:
                client.put("/api/programs/start.py", json={"source": PROGRAM}).raise_for_status()
                warm_server = daemon.app.state.ctx.sim.warm
                first_s = _first_output_s(client)  # cold; it starts the fork server
                _first_output_s(client)  # waits for the fork server's own imports
                warm, cold = [], []
                for _ in range(ROUNDS):
                    warm.append(_first_output_s(client))
                    server, warm_server._server = warm_server._server, None  # every child cold
                    try:
                        cold.append(_first_output_s(client))
                    finally:
                        warm_server._server = server
        finally:
            daemon.stop()
    return [
        Row(
            "POST to first output, warm fork server",
            statistics.median(warm) * 1000,
            "ms",
            "median; bar <= 200 ms",
        ),
        Row("POST to first output, children spawned cold", statistics.median(cold) * 1000, "ms", "median"),
        Row(
            "first run after the daemon started", first_s * 1000, "ms", "waits for the fork server's imports"
        ),
    ]
