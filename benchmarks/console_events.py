"""The console's event fan-out: a line handed to the daemon by a hub actor, to a WebSocket client.

A daemon process (benchmarks/_console_daemon.py) runs N producers that each hand it 100 lines/s through
the HubEvents seam (what a hub actor does for each line a hub prints); 20 real WebSocket clients in this
process receive them. Latency is a line's receive time at a client minus its send time (both on this
machine's clock), over every line at every client; lost counts lines some client never received (the
stream replays what a slow client missed, so it should be 0). RSS is the daemon's resident memory idle
(started, nothing connected) and after the run. The figures depend on the machine and its load: two
processes share the CPUs here, and the clients' own decoding is part of the latency. If the lines
produced fall short of hubs x rate x seconds, the daemon process itself did not get the CPU to keep the
producers' pace (a loaded machine): read the latency rows with that in mind.
"""

from __future__ import annotations

import json
import signal
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from benchmarks import Row

REPO = Path(__file__).resolve().parent.parent
CLIENTS = 20
RATE = 100  # lines per second per producer
SECONDS = 10
PRODUCERS = (2, 10)
COLLECT_TIMEOUT_S = 60


def _rss_kb(pid: int) -> int:
    for line in Path(f"/proc/{pid}/status").read_text().splitlines():
        if line.startswith("VmRSS:"):
            return int(line.split()[1])
    return 0


def _clients(url: str, token: str, producers: int) -> list[dict]:
    """CLIENTS receivers, each its own process (as each browser is), connected before output starts."""
    command = [sys.executable, "-m", "benchmarks._console_client", url, token, str(producers)]
    procs = [
        subprocess.Popen([*command, str(COLLECT_TIMEOUT_S)], cwd=REPO, stdout=subprocess.PIPE, text=True)
        for _ in range(CLIENTS)
    ]
    try:
        for proc in procs:
            assert proc.stdout.readline().strip() == "connected"
        return [json.loads(proc.stdout.readline()) for proc in procs]
    finally:
        for proc in procs:
            try:
                proc.wait(COLLECT_TIMEOUT_S)
            except subprocess.TimeoutExpired:
                proc.kill()


def _one(producers: int) -> list[Row]:
    with tempfile.TemporaryDirectory() as data_dir:
        command = [sys.executable, "-m", "benchmarks._console_daemon", data_dir]
        command += [str(producers), str(RATE), str(SECONDS), str(CLIENTS)]
        daemon = subprocess.Popen(command, cwd=REPO, stdout=subprocess.PIPE, text=True)
        try:
            ready = daemon.stdout.readline().split()
            url, token, pid = ready[1], ready[2], int(ready[3])
            time.sleep(1.0)
            idle_kb = _rss_kb(pid)
            results = _clients(url, token, producers)
            done = daemon.stdout.readline().split()
            produced, loaded_kb, cpu_s, wall_s = int(done[1]), int(done[2]), float(done[3]), float(done[4])
        finally:
            daemon.send_signal(signal.SIGINT)
            try:
                daemon.wait(20)
            except subprocess.TimeoutExpired:
                daemon.kill()
    lost = sum(produced - r["lines"] for r in results)
    counts = {k: sum(r[k] for r in results) for k in ("resync", "gap")}
    latencies = sorted(ms for r in results for ms in r["latencies_ms"])
    p50 = statistics.median(latencies)
    p99 = latencies[int(len(latencies) * 0.99) - 1]
    case = f"{producers} hubs x {RATE} lines/s, {CLIENTS} clients"
    note = f"{produced} lines x {CLIENTS} clients; resyncs {counts['resync']}, gaps {counts['gap']}"
    return [
        Row(f"{case}: latency p50", p50, "ms", "hub actor hands a line -> client has it"),
        Row(f"{case}: latency p99", p99, "ms", "target < 50 ms"),
        Row(f"{case}: lines lost", lost, "lines", note),
        Row(
            f"{case}: daemon CPU",
            cpu_s / wall_s * 100,
            "% of a core",
            f"producing and sending, {wall_s:.1f} s",
        ),
        Row(
            f"{case}: daemon CPU per line delivered",
            cpu_s * 1e6 / max(1, produced * CLIENTS),
            "us",
            "load-independent: one free core delivers 1e6/this lines/s",
        ),
        Row(f"{case}: daemon RSS idle", idle_kb / 1024, "MB", "started, no client, no hub"),
        Row(f"{case}: daemon RSS after", loaded_kb / 1024, "MB", f"after {SECONDS} s of output"),
    ]


def run() -> list[Row]:
    rows: list[Row] = []
    for producers in PRODUCERS:
        rows += _one(producers)
    return rows
