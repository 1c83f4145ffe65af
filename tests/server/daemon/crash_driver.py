"""A console daemon that records 20 runs' output through the HubEvents seam, as hub actors do, until it is
killed: run by test_crash_recovery.py as its own process, then `kill -9`ed.

stdout: `run <id>` once per run (after it is committed), then `progress <loop seconds> <json {run: lines}>`
every 50 ms of loop time: every line counted there was handed to the daemon at that loop time.
"""

from __future__ import annotations

import asyncio
import json
import sys
import time
from contextlib import asynccontextmanager
from pathlib import Path

import uvicorn

from openbricks_server.daemon.app import SERVICES, create_app
from openbricks_server.daemon.config import DaemonConfig
from openbricks_server.daemon.hub_events import HubState, OutputLine, RunStart
from openbricks_server.daemon.serve import bind, uvicorn_config

RUNS = 20


async def drive(ctx) -> None:
    events = ctx.hub_events
    loop = asyncio.get_running_loop()
    runs = {}
    for n in range(RUNS):
        hub = f"hub-{n % 4}"
        events.hub_changed(HubState(hub, hub.upper(), "virtual", hub, "running"))
        run_id = events.run_started(
            RunStart(hub, "daemon", int(time.time() * 1000), f"p{n}.py", f"print({n})\n")
        )
        runs[run_id] = 0
        print(f"run {run_id}", flush=True)
    last_progress = loop.time()
    while True:
        now_ms = int(time.time() * 1000)
        for run_id in runs:
            runs[run_id] += 1
            events.run_output(
                run_id, [OutputLine(runs[run_id], f"{run_id} line {runs[run_id]}", now_ms, now_ms)]
            )
        if loop.time() - last_progress >= 0.05:
            last_progress = loop.time()
            print(f"progress {last_progress:.4f} {json.dumps(runs)}", flush=True)
        await asyncio.sleep(0.01)


@asynccontextmanager
async def driver(ctx):
    task = asyncio.create_task(drive(ctx))
    yield
    task.cancel()


def main(data_dir: str) -> None:
    config = DaemonConfig(port=0, virtual=0, ble=False, data_dir=Path(data_dir))
    sock = bind(config)
    app = create_app(config, services=[*SERVICES, driver])
    uvicorn.Server(uvicorn_config(app)).run(sockets=[sock])


if __name__ == "__main__":
    main(sys.argv[1])
