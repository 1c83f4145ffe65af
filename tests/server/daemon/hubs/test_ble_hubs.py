"""BLE hubs in the daemon: found by the background scan through bleak's real scanner and client on
the emulated radio, with a real virtual hub process behind the radio; a link dropped mid-run is
reconnected and the output continues, complete and in order, with the gap recorded."""

from __future__ import annotations

import asyncio
import types

import pytest

from openbricks_server.compile import Program, compile_program
from openbricks_server.daemon.hubs.backend import start_virtual_hub
from openbricks_server.daemon.hubs.manager import HubManager
from tests.server.daemon.hubs.recording_events import RecordingEvents
from tests.server.link.fake_ble_backend import FakeRadio, LinkTiming
from tests.server.link.pty_bridge import PtyHubBridge

pytestmark = pytest.mark.e2e

LAPS = 40
PROGRAM = f"from openbricks.tools import wait\nfor i in range({LAPS}):\n    print('lap', i)\n    wait(50)\n"


@pytest.fixture
def data_dir(tmp_path, monkeypatch):
    monkeypatch.setenv("OPENBRICKS_DATA_DIR", str(tmp_path))
    return tmp_path


async def ble_daemon(data_dir, names, timing=None):
    radio = FakeRadio()
    processes = []
    for name in names:
        hub = await start_virtual_hub(name, hub_dir=str(data_dir / "virtual-hubs" / name))
        processes.append(hub)
        radio.add_hub(PtyHubBridge(name, hub.pty), timing=timing or LinkTiming())
    events = RecordingEvents()
    config = types.SimpleNamespace(virtual=0, ble=True, data_dir=data_dir)
    manager = HubManager(
        config,
        events,
        None,
        ble_client_backend=radio.client_backend,
        ble_scanner_backend=radio.scanner_backend,
    )
    manager.scan_s, manager.scan_pause_s = 0.5, 0.5
    await manager.start()
    async with asyncio.timeout(20):
        while {a.name for a in manager.list() if a.state.kind == "ble"} != set(names):
            await asyncio.sleep(0.1)

    async def close():
        await manager.close()
        for peripheral in radio.peripherals.values():
            peripheral.hub.close()
        for hub in processes:
            await hub.close()

    return manager, events, radio, close


def test_a_link_dropped_mid_run_reconnects_and_the_output_continues_with_the_gap_recorded(data_dir):
    async def scenario():
        manager, events, radio, close = await ble_daemon(
            data_dir, ["BleBot"], LinkTiming(supervision_timeout_ms=400)
        )
        try:
            (hub,) = [a for a in manager.list() if a.state.kind == "ble"]
            assert hub.hub_id.startswith("ble:24:0A:C4:") and hub.state.status == "offline"
            await hub.connect(30)
            run_id = await hub.run(compile_program(Program("laps.py", PROGRAM)), who="coach")
            await events.until(lambda: len(events.runs[run_id].lines) >= 8)
            (peripheral,) = radio.peripherals.values()
            peripheral.drop()
            await events.until(lambda: events.runs[run_id].ended is not None, 60)
            return events, run_id, hub.hub_id, peripheral.connections
        finally:
            await close()

    events, run_id, hub_id, connections = asyncio.run(scenario())
    run = events.runs[run_id]
    assert run.ended[0] == "finished"
    assert run.texts == [f"lap {i}" for i in range(LAPS)]  # none lost, none twice
    assert [line.line_no for line in run.lines] == list(range(1, LAPS + 1))
    ((reason, since, until),) = run.gaps
    assert reason.startswith("the hub disconnected") and until is not None and 0 <= until - since < 10_000
    statuses = events.statuses(hub_id)
    at = statuses.index("running")
    assert statuses[at : at + 3] == ["running", "connecting", "running"]
    assert connections == 2
