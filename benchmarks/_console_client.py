"""One WebSocket client of the console's event stream, in its own process (as each browser is), for
`benchmarks/console_events.py`: `python -m benchmarks._console_client URL TOKEN RUNS TIMEOUT_S`.

Receives until RUNS runs have ended, then prints one JSON line: each line's latency (receive time minus the
send time in its text, ms), how many distinct lines arrived, and the resync/gap messages seen.
"""

from __future__ import annotations

import asyncio
import contextlib
import json
import sys
import time

from websockets.asyncio.client import connect


async def receive(url: str, token: str, runs: int, timeout_s: float) -> dict:
    counts = {"resync": 0, "gap": 0, "run_ended": 0}
    latencies, seen = [], set()
    ws_url = url.replace("http://", "ws://") + "/api/events"
    headers = {"Authorization": f"Bearer {token}"}
    async with connect(ws_url, origin=url, additional_headers=headers, max_size=None, compression=None) as ws:
        print("connected", flush=True)
        # One deadline for the whole stream: a wait_for() per message would start a task for each one,
        # and twenty such clients on two cores would cost more than the daemon they measure.
        with contextlib.suppress(TimeoutError):
            async with asyncio.timeout(timeout_s):
                async for text in ws:
                    now = time.time()
                    message = json.loads(text)
                    kind = message["type"]
                    if kind == "output":
                        for line in message["data"]["lines"]:
                            latencies.append(round((now - float(line["text"])) * 1000, 3))
                            seen.add((message["run"], line["line_no"]))
                    elif kind in counts:
                        counts[kind] += 1
                        if counts["run_ended"] >= runs:
                            break
    return {"latencies_ms": latencies, "lines": len(seen), **counts}


if __name__ == "__main__":
    url, token, runs, timeout_s = sys.argv[1], sys.argv[2], int(sys.argv[3]), float(sys.argv[4])
    print(json.dumps(asyncio.run(receive(url, token, runs, timeout_s))), flush=True)
