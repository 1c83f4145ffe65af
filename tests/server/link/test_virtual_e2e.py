"""End to end: the link layer and raw-REPL client against real virtual hub processes
(`python -m openbricks_sim.virtual_hub`), over their stdio pipes and over their pty."""

import asyncio
import os

import pytest

from openbricks_server.link import LinkDropped
from openbricks_server.link.raw_repl import RawRepl
from openbricks_server.link.virtual import VirtualHubLink, spawn_pty_hub

pytestmark = pytest.mark.e2e

PROGRAM = b"import time\nfor lap in range(5):\n    print('lap', lap)\n    time.sleep_ms(50)\n"


def run(coro, timeout_s=120):
    async def bounded():
        async with asyncio.timeout(timeout_s):
            return await coro

    return asyncio.run(bounded())


def test_upload_and_run_on_a_virtual_hub_over_its_pipes(tmp_path):
    async def scenario():
        link = VirtualHubLink("RobotV", hub_dir=str(tmp_path / "RobotV"), extra_args=["--speed", "max"])
        await link.connect()
        try:
            repl = RawRepl(link, timeout_s=30)
            await repl.enter()  # the hub boots into its launcher: enter interrupts it
            info = await repl.info()
            assert info.firmware.startswith("2.7.1") and not info.accepts_mpy
            staged = await repl.put("/program.py", PROGRAM)
            assert staged["bytes"] == len(PROGRAM)
            chunks = []
            result = await repl.run("/program.py", on_output=chunks.append, timeout_s=60)
            assert result["outcome"] == "finished"
            assert b"".join(chunks) == b"".join(b"lap %d\r\n" % lap for lap in range(5))
            blob = os.urandom(9000)
            await repl.put("/blob.bin", blob)
            assert await repl.get("/blob.bin") == blob
        finally:
            await link.close()
        assert (tmp_path / "RobotV").exists()  # its flash lives in the hub directory

    run(scenario())


def test_a_virtual_hub_over_its_pty_and_its_end_as_a_drop(tmp_path):
    async def scenario():
        hub = await spawn_pty_hub("RobotP", hub_dir=str(tmp_path / "RobotP"))
        try:
            repl = RawRepl(hub.link, timeout_s=30)
            await repl.enter()
            assert (await repl.exec("print(sum(range(10)))")).stdout == b"45\r\n"
            dropped = asyncio.Event()
            hub.link.on_drop(lambda _drop: dropped.set())
            hub.process.kill()
            async with asyncio.timeout(5):
                await dropped.wait()
            with pytest.raises(LinkDropped, match="link to RobotP dropped"):
                await repl.exec("print(1)")
        finally:
            await hub.stop()

    run(scenario())
