"""A console sim run's child comes from the daemon's warm fork server, and is steered like a spawned one."""

import asyncio
import json
import os

import pytest

from openbricks_server.daemon.sim.warm import WarmProcess, WarmServer
from openbricks_sim.job import SimJob

pytestmark = [pytest.mark.e2e, pytest.mark.skipif(not hasattr(os, "fork"), reason="fork() is POSIX")]

TICKER = "import time\nprint('first')\nwhile True:\n    time.sleep_ms(50)\n"


def _parent_pid(pid: int) -> int:
    with open(f"/proc/{pid}/stat", encoding="ascii") as stat:
        return int(stat.read().rsplit(")", 1)[1].split()[1])


async def _scenario(tmp_path):
    program = tmp_path / "ticker.py"
    program.write_text(TICKER, encoding="utf-8")
    job = SimJob(str(program), limit_ms=10**9, wall_limit_s=60, hub_dir=str(tmp_path / "flash"))
    spec = tmp_path / "job.json"
    spec.write_text(
        json.dumps({"job": job.to_dict(), "recording": str(tmp_path / "run.viser")}), encoding="utf-8"
    )
    warm = WarmServer()
    try:
        with open(tmp_path / "child.log", "wb") as log:
            start = {"cwd": str(tmp_path), "stderr": log.fileno(), "limit": 2**20}
            assert await warm.start("console_job", [str(spec)], **start) is None, "the first goes cold"
            process = await warm.start("console_job", [str(spec)], **start)
        assert isinstance(process, WarmProcess)
        assert _parent_pid(process.pid) == warm._server.process.pid, "forked by the fork server"
        kinds = []
        while "output" not in kinds:
            event = json.loads(await asyncio.wait_for(process.stdout.readline(), 60))
            kinds.append(event["type"])
        assert kinds[0] == "ready" and event["text"].strip() == "first"
        process.stdin.write(b'{"cmd": "stop"}\n')
        while event["type"] != "result":
            event = json.loads(await asyncio.wait_for(process.stdout.readline(), 60))
        assert event["result"]["exit"] == "stopped"
        assert await asyncio.wait_for(process.wait(), 30) == 0 and process.returncode == 0
    finally:
        await warm.close()


def test_a_run_child_is_forked_warm_steered_and_reaped(tmp_path):
    asyncio.run(_scenario(tmp_path))
