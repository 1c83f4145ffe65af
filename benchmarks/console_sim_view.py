"""Watching a sim run through the console: how much do 1, 5 and 20 viewers of its 3D view slow it?

A real daemon (uvicorn on 127.0.0.1, in this process) starts the same sim run (a drive base going
back and forth, paced at PACE times real time, so the view draws the same frames per simulated second
whatever the machine's load) once per viewer count. The viewers are WebSockets in
one other process connected to the run's view through the daemon's port (the proxy, as browsers
would be), each reading everything viser sends. Once they are all connected, the run's simulated
time and the run process's CPU time are read twice, WINDOW_S apart.

The run's CPU time per simulated second is what watching costs the run (viser encodes and sends
each frame on the run's own threads, once per connection), and it does not depend on what else the
machine is doing: its growth over the no-viewer run is the slowdown a run going flat out on a core of
its own would see. The run's speed (simulated seconds per wall-clock second, PACE when it keeps up)
is the slowdown as measured here. The connections row counts the run's viser server's clients: the
daemon shares one among all browsers. The daemon's own CPU (the proxy) runs in another process,
beside the run, not in it. Each count is measured ROUNDS times, interleaved, and the median kept.
"""

from __future__ import annotations

import json
import statistics
import subprocess
import sys
import tempfile
import threading
import time
from dataclasses import replace
from pathlib import Path

import httpx
import uvicorn

from benchmarks import Row
from benchmarks._proc import proc_stat
from tests.server.daemon.sim.proc_net import connections_to

REPO = Path(__file__).resolve().parent.parent
VIEWERS = (0, 1, 5, 20)
ROUNDS = 2
WINDOW_S = 8.0
PACE = 2.0
PROGRAM = """\
from openbricks.drivers.st3032 import ST3032Motor
from openbricks.robotics import DriveBase

left = ST3032Motor(servo_id=1, uart_id=1, tx=14, rx=41)
right = ST3032Motor(servo_id=2, uart_id=1, tx=14, rx=41, invert=True)
db = DriveBase(left, right, wheel_diameter_mm=88, axle_track_mm=138)
while True:
    db.straight(300)
    db.turn(180)
"""


class _Daemon:
    def __init__(self, data_dir: Path):
        from openbricks_server.daemon.app import create_app
        from openbricks_server.daemon.config import DaemonConfig
        from openbricks_server.daemon.serve import bind, uvicorn_config

        config = DaemonConfig(host="127.0.0.1", port=0, virtual=0, ble=False, data_dir=data_dir)
        sock = bind(config)
        self.config = replace(config, port=sock.getsockname()[1])
        self.app = create_app(self.config)
        self.server = uvicorn.Server(uvicorn_config(self.app))
        self.thread = threading.Thread(target=self.server.run, kwargs={"sockets": [sock]}, daemon=True)
        self.thread.start()
        while not self.server.started:
            time.sleep(0.05)
        self.url = self.config.url()
        self.token = self.app.state.ctx.auth.local_token

    def stop(self):
        self.server.should_exit = True
        self.thread.join(30)


def _sample(client: httpx.Client, run_id: str, pid: int) -> tuple[float, int, float, float]:
    """(wall s, simulated ms, the run's CPU s, this daemon's CPU s), now."""
    sim_ms = client.get(f"/api/sim/runs/{run_id}").json()["sim_ms"]
    return time.monotonic(), sim_ms, proc_stat(pid)[0], time.process_time()


def _measure(daemon: _Daemon, client: httpx.Client, viewers: int) -> dict:
    """One run watched by `viewers`: its speed, its CPU per simulated s, the daemon's CPU share, and
    the bytes per second each viewer received."""
    posted = time.monotonic()
    run = client.post(
        "/api/sim/runs",
        json={"program": "bench.py", "speed": PACE, "limit_ms": 3_600_000, "wall_limit_s": 600},
    ).json()
    run_id = run["run_id"]
    while client.get(f"/api/sim/runs/{run_id}").json()["state"] != "running":
        time.sleep(0.05)
    start_s = time.monotonic() - posted
    job = daemon.app.state.ctx.sim.live[run_id]
    pid = job._process.pid
    clients = None
    try:
        if viewers:
            ws_url = f"{daemon.url.replace('http://', 'ws://')}/sim/runs/{run_id}/view"
            clients = subprocess.Popen(
                [
                    sys.executable,
                    "-m",
                    "benchmarks._sim_view_clients",
                    ws_url,
                    daemon.url,
                    daemon.token,
                    str(viewers),
                    str(WINDOW_S + 1),
                ],
                cwd=REPO,
                stdout=subprocess.PIPE,
                text=True,
            )
            assert clients.stdout.readline().strip() == "connected"
        time.sleep(1.0)  # the viewers' initial scene is sent and drawn
        connections = connections_to(job.port)
        t0, sim0, cpu0, own0 = _sample(client, run_id, pid)
        time.sleep(WINDOW_S)
        t1, sim1, cpu1, own1 = _sample(client, run_id, pid)
        per_viewer = 0.0
        if clients is not None:
            counts = json.loads(clients.stdout.readline())
            per_viewer = statistics.mean(c["bytes"] for c in counts) / (WINDOW_S + 1)
        sim_s = (sim1 - sim0) / 1000
        return {
            "speed": sim_s / (t1 - t0),
            "cpu_per_sim_s": (cpu1 - cpu0) / sim_s,
            "daemon_cpu": 100 * (own1 - own0) / (t1 - t0),
            "traffic": per_viewer,
            "connections": connections,
            "start_s": start_s,
        }
    finally:
        client.post(f"/api/sim/runs/{run_id}/stop")
        if clients is not None:
            clients.wait(30)


def run() -> list[Row]:
    with tempfile.TemporaryDirectory() as tmp:
        daemon = _Daemon(Path(tmp) / "data")
        try:
            with httpx.Client(
                base_url=daemon.url, headers={"Authorization": f"Bearer {daemon.token}"}, timeout=60
            ) as client:
                client.put("/api/programs/bench.py", json={"source": PROGRAM}).raise_for_status()
                figures: dict[int, list[dict]] = {n: [] for n in VIEWERS}
                for _ in range(ROUNDS):
                    for n in VIEWERS:
                        figures[n].append(_measure(daemon, client, n))
        finally:
            daemon.stop()

    def median(n, key):
        return statistics.median(f[key] for f in figures[n])

    base_cpu, base_speed = median(0, "cpu_per_sim_s"), median(0, "speed")
    rows = [
        Row("no viewer: run CPU per sim s", 1000 * base_cpu, "ms"),
        Row("no viewer: run speed", base_speed, "sim s/s", f"paced at {PACE:g}x"),
        Row(
            "sim job start latency",
            statistics.median(f["start_s"] for n in VIEWERS for f in figures[n]),
            "s",
            "POST /api/sim/runs to running (process, imports, world, view), median of every run",
        ),
    ]
    for n in VIEWERS[1:]:
        cpu, speed = median(n, "cpu_per_sim_s"), median(n, "speed")
        rows += [
            Row(f"{n} viewer(s): run CPU per sim s", 1000 * cpu, "ms"),
            Row(
                f"{n} viewer(s): slowdown from CPU",
                100 * (1 - base_cpu / cpu),
                "%",
                "a run alone on its core",
            ),
            Row(f"{n} viewer(s): slowdown measured", 100 * (1 - speed / base_speed), "%", "wall clock"),
            Row(f"{n} viewer(s): connections to the run", median(n, "connections"), "", "viser's clients"),
            Row(
                f"{n} viewer(s): daemon CPU",
                median(n, "daemon_cpu"),
                "% of a core",
                "the proxy, beside the run",
            ),
            Row(f"{n} viewer(s): view traffic", median(n, "traffic") / 1000, "kB/s each"),
        ]
    return rows
