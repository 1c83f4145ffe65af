"""Viewers of one sim run's 3D view, for `benchmarks/console_sim_view.py`:
`python -m benchmarks._sim_view_clients WS_URL ORIGIN TOKEN N SECONDS`.

Opens N WebSockets to the view through the daemon (as N browsers would, with viser's subprotocol),
prints `connected` once every one has its first message, reads for SECONDS, then prints one JSON
line: bytes and messages received per viewer.
"""

from __future__ import annotations

import asyncio
import json
import sys
import time

import viser
from websockets.asyncio.client import connect


async def viewer(url: str, origin: str, token: str, first: asyncio.Event, until: list, counts: dict):
    async with connect(
        url,
        origin=origin,
        additional_headers={"Authorization": f"Bearer {token}"},
        subprotocols=[f"viser-v{viser.__version__}"],
        max_size=None,
        compression=None,
        open_timeout=30,
        proxy=None,
    ) as socket:
        await socket.recv()
        first.set()
        while not until or time.monotonic() < until[0]:
            try:
                message = await asyncio.wait_for(socket.recv(), 1.0)
            except TimeoutError:
                continue
            counts["bytes"] += len(message)
            counts["messages"] += 1


async def main(url: str, origin: str, token: str, n: int, seconds: float) -> None:
    firsts = [asyncio.Event() for _ in range(n)]
    counts = [{"bytes": 0, "messages": 0} for _ in range(n)]
    until: list = []
    tasks = [
        asyncio.create_task(viewer(url, origin, token, f, until, c))
        for f, c in zip(firsts, counts, strict=True)
    ]
    await asyncio.wait_for(asyncio.gather(*(f.wait() for f in firsts)), 120)
    print("connected", flush=True)
    until.append(time.monotonic() + seconds)
    await asyncio.gather(*tasks)
    print(json.dumps(counts), flush=True)


if __name__ == "__main__":
    url, origin, token, n, seconds = sys.argv[1:6]
    asyncio.run(main(url, origin, token, int(n), float(seconds)))
