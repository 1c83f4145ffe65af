"""Flashing many hubs at once through the console: one port against twenty, wall time from the request to
the last result.

Boards: real virtual hub processes (their ptys stand in for USB ports, so reading the old firmware,
naming the hub and recording provenance really go through each hub's raw REPL). esptool: the tests'
fake (tests/server/flash/fake_esptool.py) with a write that takes WRITE_S seconds, a stand-in for the
USB transfer (a 1.5 MB image at 460800 baud takes about 35 s on a real board). The daemon runs in this
process (uvicorn on 127.0.0.1); each flash job runs its esptool as a separate process, as it would.
"""

from __future__ import annotations

import stat
import sys
import tempfile
import time
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

from benchmarks import Row

REPO = Path(__file__).resolve().parent.parent
if str(REPO) not in sys.path:
    sys.path.insert(0, str(REPO))  # the boards and the fake esptool live with the tests

BOARDS = 20
WRITE_S = 4.0
STARTING_AT_ONCE = 4


def _fake_esptool(folder: Path) -> Path:
    script = folder / "esptool"
    fake = REPO / "tests" / "server" / "flash" / "fake_esptool.py"
    script.write_text(f'#!/bin/sh\nexec "{sys.executable}" "{fake}" "$@"\n')
    script.chmod(script.stat().st_mode | stat.S_IXUSR)
    return script


def _flash(client, boards, firmware: str, tag: str) -> tuple[float, list[float]]:
    """Wall time of one request flashing `boards`, and each job's own duration."""
    targets = [{"port": b.pty, "name": f"{tag}{i:02d}"} for i, b in enumerate(boards, 1)]
    started = time.monotonic()
    jobs = client.post("/api/flash", json={"targets": targets, "firmware": firmware}).json()["jobs"]
    done = [client.get(f"/api/flash/{j['job_id']}", params={"wait_s": 600}, timeout=630).json() for j in jobs]
    wall = time.monotonic() - started
    failed = [j for j in done if j["state"] != "done"]
    if failed:
        raise RuntimeError(f"{len(failed)} flash jobs failed: {failed[0]['message']}")
    return wall, [(j["ended_ms"] - j["started_ms"]) / 1000 for j in done]


def run() -> list[Row]:
    import os

    from tests.server.commands.conftest import HubProcess
    from tests.server.daemon.conftest import start_daemon
    from tests.server.flash.images import build_image

    rows: list[Row] = []
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        saved = {
            k: os.environ.get(k) for k in ("OPENBRICKS_ESPTOOL", "FAKE_ESPTOOL_LOG", "FAKE_ESPTOOL_WRITE_S")
        }
        os.environ.update(
            OPENBRICKS_ESPTOOL=str(_fake_esptool(folder)),
            FAKE_ESPTOOL_LOG=str(folder / "calls.jsonl"),
            FAKE_ESPTOOL_WRITE_S=str(WRITE_S),
        )
        with ThreadPoolExecutor(STARTING_AT_ONCE) as pool:
            boards = list(pool.map(lambda i: HubProcess(f"Board{i:02d}", folder / "boards"), range(BOARDS)))
        daemon = start_daemon(folder / "console")
        try:
            with daemon.client() as client:
                firmware = client.post(
                    "/api/flash/firmware",
                    content=build_image("esp32s3", version="2.8.0"),
                    headers={"Content-Type": "application/octet-stream"},
                ).json()["firmware_id"]
                one, _ = _flash(client, boards[:1], firmware, "One")
                many, each = _flash(client, boards, firmware, "Many")
        finally:
            daemon.stop()
            with ThreadPoolExecutor(BOARDS) as pool:
                list(pool.map(HubProcess.stop, boards))
            for key, value in saved.items():
                if value is None:
                    os.environ.pop(key, None)
                else:
                    os.environ[key] = value
    note = f"esptool write {WRITE_S:g} s"
    rows.append(Row("flash 1 port: request to result", one, "s", note))
    rows.append(Row(f"flash {BOARDS} ports at once: request to last result", many, "s", note))
    rows.append(
        Row(f"{BOARDS} ports vs {BOARDS} x 1 port", BOARDS * one / many, "x", "speed-up over one at a time")
    )
    rows.append(Row(f"{BOARDS} ports: slowest job", max(each), "s", "queue wait excluded"))
    return rows
