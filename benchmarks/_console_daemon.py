"""A console daemon with N producers feeding output lines through the HubEvents seam, for
`benchmarks/console_events.py`: `python -m benchmarks._console_daemon DATA_DIR HUBS RATE SECONDS CLIENTS`.

Prints `ready <url> <token> <pid>`; once CLIENTS WebSocket clients are subscribed it produces for SECONDS
(each hub one line every 1/RATE s, each line's text its send time), prints
`done <lines> <rss_kb> <cpu_s> <wall_s>`, and serves until killed.
"""

from __future__ import annotations

import asyncio
import contextlib
import os
import sys
import time
from contextlib import asynccontextmanager
from pathlib import Path

import uvicorn

from openbricks_server.daemon.app import SERVICES, create_app
from openbricks_server.daemon.config import DaemonConfig
from openbricks_server.daemon.hub_events import HubState, OutputLine, RunStart
from openbricks_server.daemon.serve import bind, uvicorn_config


def rss_kb() -> int:
    for line in Path("/proc/self/status").read_text().splitlines():
        if line.startswith("VmRSS:"):
            return int(line.split()[1])
    return 0


async def produce(ctx, hubs: int, rate: float, seconds: float, clients: int) -> None:
    events = ctx.hub_events
    while ctx.events.subscribers < clients:
        await asyncio.sleep(0.05)
    await asyncio.sleep(0.5)  # let the clients' hello settle

    async def hub(n: int) -> int:
        hub_id = f"bench-{n}"
        events.hub_changed(HubState(hub_id, f"Bench{n}", "virtual", hub_id, "running"))
        run_id = events.run_started(RunStart(hub_id, "daemon", int(time.time() * 1000), "bench.py", "pass\n"))
        period = 1.0 / rate
        start = time.monotonic()
        line_no = 0
        while (elapsed := time.monotonic() - start) < seconds:
            due = int(elapsed / period) + 1  # catch up after a late wake-up, like a hub's buffered output
            while line_no < due:
                line_no += 1
                now = time.time()
                events.run_output(run_id, [OutputLine(line_no, f"{now:.6f}", None, int(now * 1000))])
            await asyncio.sleep(period - (time.monotonic() - start) % period)
        events.run_ended(run_id, "finished", None, int(time.time() * 1000))
        return line_no

    cpu, wall = time.process_time(), time.monotonic()
    produced = await asyncio.gather(*(hub(n) for n in range(hubs)))
    await asyncio.sleep(1.0)  # the last lines reach the clients
    cpu, wall = time.process_time() - cpu, time.monotonic() - wall
    print(f"done {sum(produced)} {rss_kb()} {cpu:.3f} {wall:.3f}", flush=True)


def main(data_dir: str, hubs: str, rate: str, seconds: str, clients: str) -> None:
    config = DaemonConfig(port=0, virtual=0, ble=False, data_dir=Path(data_dir))
    sock = bind(config)

    @asynccontextmanager
    async def producer(ctx):
        url = ctx.config.url(sock.getsockname()[1])
        print(f"ready {url} {ctx.auth.local_token} {os.getpid()}", flush=True)
        task = asyncio.create_task(produce(ctx, int(hubs), float(rate), float(seconds), int(clients)))
        yield
        task.cancel()

    app = create_app(config, services=[*SERVICES, producer])
    with contextlib.suppress(KeyboardInterrupt):  # the benchmark ends it with SIGINT
        uvicorn.Server(uvicorn_config(app)).run(sockets=[sock])


if __name__ == "__main__":
    main(*sys.argv[1:])
