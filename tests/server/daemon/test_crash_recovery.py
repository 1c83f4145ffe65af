"""`kill -9` of the daemon while runs print: on restart the database is intact, every run is there,
marked interrupted, every line the daemon had held for one flush interval was kept, and a hub's run log
fills in the lines the daemon never saw."""

import json
import os
import re
import signal
import sqlite3
import subprocess
import sys
import time
from pathlib import Path

import httpx
import pytest
from websockets.sync.client import connect

from openbricks_server.daemon.config import DB_FILENAME

REPO = Path(__file__).resolve().parents[3]
FLUSH_MARGIN_S = 0.1  # loop time after which a line handed to the daemon must be on disk (flush: 20 ms)


def _driver(data_dir):
    return subprocess.Popen(
        [sys.executable, "-m", "tests.server.daemon.crash_driver", str(data_dir)],
        cwd=REPO,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )


@pytest.mark.e2e
def test_kill_9_during_20_runs_loses_nothing_that_was_flushed(tmp_path):
    data_dir = tmp_path / "console"
    daemon = _driver(data_dir)
    runs, progress = [], []
    try:
        deadline = time.monotonic() + 60
        while len(progress) < 20:  # a second of output at least
            assert time.monotonic() < deadline, daemon.stderr.read()
            line = daemon.stdout.readline()
            assert line, daemon.stderr.read()
            kind, _, rest = line.strip().partition(" ")
            if kind == "run":
                runs.append(rest)
            else:
                stamp, _, counts = rest.partition(" ")
                progress.append((float(stamp), json.loads(counts)))
        os.kill(daemon.pid, signal.SIGKILL)
        daemon.wait(10)
    finally:
        if daemon.poll() is None:
            daemon.kill()
    assert len(runs) == 20
    newest = progress[-1][0]
    settled = [counts for stamp, counts in progress if stamp <= newest - FLUSH_MARGIN_S][-1]

    database = sqlite3.connect(data_dir / DB_FILENAME)
    assert database.execute("PRAGMA integrity_check").fetchone()[0] == "ok"
    stored = dict(database.execute("SELECT run_id, count(*) FROM output_lines GROUP BY run_id").fetchall())
    highest = dict(
        database.execute("SELECT run_id, max(line_no) FROM output_lines GROUP BY run_id").fetchall()
    )
    database.close()
    for run_id in runs:
        assert stored[run_id] == highest[run_id], "line numbers must have no holes"
        assert stored[run_id] >= settled[run_id], f"{run_id}: lines held past a flush were lost"

    env = dict(os.environ, OPENBRICKS_RUNTIME_DIR=str(tmp_path / "run"))
    restarted = subprocess.Popen(
        [
            sys.executable,
            "-m",
            "openbricks_server.cli",
            "console",
            "--port",
            "0",
            "--virtual",
            "0",
            "--no-ble",
            "--data-dir",
            str(data_dir),
        ],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        env=env,
    )
    try:
        match = re.search(r"open (http://\S+)/\?token=(\S+)", restarted.stdout.readline())
        assert match, restarted.stderr.read()
        url, token = match.groups()
        with httpx.Client(base_url=url, headers={"Authorization": f"Bearer {token}"}, timeout=10) as client:
            listed = client.get("/api/runs", params={"limit": 100}).json()
            assert sorted(r["run_id"] for r in listed) == sorted(runs)
            assert {r["outcome"] for r in listed} == {"interrupted"}
            assert all("daemon stopped" in r["detail"] for r in listed)
            one = client.get(f"/api/runs/{runs[0]}/output", params={"limit": 10_000}).json()
            assert [ln["line_no"] for ln in one["lines"]] == list(range(1, stored[runs[0]] + 1))
    finally:
        restarted.send_signal(signal.SIGINT)
        try:
            restarted.wait(30)
        except subprocess.TimeoutExpired:
            restarted.kill()


def _start_console(tmp_path, data_dir, virtual):
    env = dict(os.environ, OPENBRICKS_RUNTIME_DIR=str(tmp_path / "run"), OPENBRICKS_DATA_DIR=str(tmp_path))
    console = subprocess.Popen(
        [
            sys.executable,
            "-m",
            "openbricks_server.cli",
            "console",
            "--port",
            "0",
            "--virtual",
            str(virtual),
            "--no-ble",
            "--data-dir",
            str(data_dir),
        ],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        env=env,
    )
    match = re.search(r"open (http://\S+)/\?token=(\S+)", console.stdout.readline())
    assert match, console.stderr.read()
    url, token = match.groups()
    return console, url, httpx.Client(base_url=url, headers={"Authorization": f"Bearer {token}"}, timeout=30)


def _hub_processes(data_dir) -> list[int]:
    found = subprocess.run(
        ["pgrep", "-f", "--", f"--dir {data_dir}/virtual-hubs/"], capture_output=True, text=True
    )
    return [int(pid) for pid in found.stdout.split()]


def _until(check, timeout_s=90, step_s=0.3):
    deadline = time.monotonic() + timeout_s
    while not (result := check()):
        assert time.monotonic() < deadline, "timed out"
        time.sleep(step_s)
    return result


PROGRAM = """import time
for i in range(40):
    print('line', i)
    time.sleep(0.05)
time.sleep(1)
print('end')
"""


@pytest.mark.e2e
def test_after_kill_9_the_hubs_run_log_fills_in_what_the_daemon_never_saw(tmp_path):
    data_dir = tmp_path / "console"
    console, url, client = _start_console(tmp_path, data_dir, virtual=1)
    try:
        _until(lambda: [h for h in client.get("/api/hubs").json()["hubs"] if h["status"] == "idle"])
        headers = {"Authorization": client.headers["Authorization"]}
        with connect(
            url.replace("http://", "ws://") + "/api/events", origin=url, additional_headers=headers
        ) as ws:
            started = client.post("/api/hubs/SimHub-1/run", json={"source": PROGRAM, "name": "count.py"})
            assert started.status_code == 200, started.text
            run_id = started.json()["run_id"]
            seen = 0
            while seen < 10:  # the daemon is mid-run: it has shown 10 lines
                message = json.loads(ws.recv(timeout=30))
                if message["type"] == "output" and message["run"] == run_id:
                    seen = max(line["line_no"] for line in message["data"]["lines"])
        hubs = _hub_processes(data_dir)
        assert len(hubs) == 1
        os.kill(console.pid, signal.SIGKILL)
        console.wait(10)
        # The hub runs on without its host, as a real one does, keeps its run log, and switches
        # itself off once the program has ended: no orphan outlives the console.
        _until(lambda: not _hub_processes(data_dir), timeout_s=30)

        console, url, client = _start_console(tmp_path, data_dir, virtual=1)
        run = _until(lambda: (r := client.get(f"/api/runs/{run_id}").json())["line_count"] >= 41 and r)
        lines = client.get(f"/api/runs/{run_id}/output").json()["lines"]
        assert [line["text"] for line in lines] == [f"line {i}" for i in range(40)] + ["end"]
        assert run["outcome"] == "interrupted"
        assert [r["run_id"] for r in client.get("/api/runs").json()] == [run_id]  # one run, not two
    finally:
        console.send_signal(signal.SIGINT)
        try:
            console.wait(30)
        except subprocess.TimeoutExpired:
            console.kill()
        for pid in _hub_processes(data_dir):
            os.kill(pid, signal.SIGKILL)
