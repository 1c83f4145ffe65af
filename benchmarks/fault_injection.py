"""The run protocol under injected faults: 10,000 seeded host sessions, each with one fault.

A session is what `openbricks run` and `openbricks log` do (enter the raw REPL, info, upload by
raw-paste host calls, run with streamed output, read the run log back) over a link that drops,
delays, duplicates, reorders or truncates bytes, or disconnects, at a seeded byte of a seeded
direction, so every phase gets hit (tests/server/link/faults.py, fault_harness.py). Nine in ten
seeds run on the emulated BLE radio (bleak's real client, the scripted hub), one in ten on a real
virtual hub's pty.

Figures: hangs (a session still going after every timeout it has should have fired; must be 0),
failures by named error kind (each within its timeout), errors that are not named link errors
(bugs; must be 0), and lines lost: lines the hub's run log holds that a session which reported the
run as finished did not show, or read back, intact (must be 0). One seed per kind is printed on
stderr to reproduce it. `OPENBRICKS_FAULT_SEEDS` sets the number of seeds (default 10,000).
"""

from __future__ import annotations

import asyncio
import os
import sys
import tempfile
from pathlib import Path

from benchmarks import Row

REPO = Path(__file__).resolve().parent.parent
if str(REPO) not in sys.path:
    sys.path.insert(0, str(REPO))  # the emulated radio and the fault harness live with the tests

SEEDS_ENV = "OPENBRICKS_FAULT_SEEDS"
PTY_EVERY = 10  # one seed in ten runs on the virtual hub's pty


async def _sessions(seeds: int):
    from tests.server.link.fault_harness import BleBench, PtyBench, Tally, run_seeds

    tallies = {}
    with tempfile.TemporaryDirectory(prefix="openbricks-faults-") as tmp:
        for bench, chosen in (
            (BleBench(), [s for s in range(seeds) if s % PTY_EVERY]),
            (PtyBench(Path(tmp) / "FaultPty"), [s for s in range(seeds) if not s % PTY_EVERY]),
        ):
            await bench.start()
            try:
                tallies[bench.transport] = await run_seeds(bench, chosen, Tally())
            finally:
                await bench.stop()
    return tallies


def run() -> list[Row]:
    seeds = int(os.environ.get(SEEDS_ENV, "10000"))
    tallies = asyncio.run(_sessions(seeds))
    rows = []
    for transport, tally in tallies.items():
        where = "emulated BLE" if transport == "ble" else "virtual hub pty"
        rows.append(Row(f"{where}: sessions", tally.sessions, "seeds", f"{tally.ok} completed"))
        rows.append(Row(f"{where}: hangs", tally.hangs, "sessions", "must be 0"))
        for kind, count in sorted(tally.failures.items(), key=lambda item: -item[1]):
            rows.append(Row(f"{where}: failed with {kind}", count, "sessions"))
        for kind, count in tally.unnamed.items():
            rows.append(Row(f"{where}: UNNAMED {kind}", count, "sessions", "must be 0"))
        rows.append(
            Row(f"{where}: slowest failure", tally.slowest_failure_s, "s", "a named error within its timeout")
        )
        rows.append(
            Row(
                f"{where}: lines lost",
                tally.lines_lost,
                "lines",
                f"of {tally.lines_logged} logged; must be 0",
            )
        )
        for kind, (transport_name, seed, faults) in sorted(tally.examples.items()):
            print(
                f"fault_injection: {kind}: {transport_name} seed {seed} ({'; '.join(faults)})",
                file=sys.stderr,
            )
    return rows
