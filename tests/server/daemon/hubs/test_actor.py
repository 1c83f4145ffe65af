"""Hub actors on real virtual hub processes: runs on two hubs at once kept apart, one operation at a
time (409 naming the holder), stop and stop-all pre-empting, a button-started run captured live, and
every run's log read back with the key that matches it to the live capture."""

from __future__ import annotations

import asyncio
import json
import re
import types
from pathlib import Path

import pytest

from openbricks_server.compile import Program, compile_program
from openbricks_server.daemon.hubs.errors import HubBusyError, HubLinkError, HubOfflineError
from openbricks_server.daemon.hubs.manager import HubManager
from openbricks_server.link.discovery import control
from tests.server.daemon.hubs.recording_events import RecordingEvents

pytestmark = pytest.mark.e2e


def program(source: str, name: str = "mission.py") -> Program:
    return compile_program(Program(name, source))


async def started_hubs(data_dir: Path, count: int):
    events = RecordingEvents()
    config = types.SimpleNamespace(virtual=count, world=None, ble=False, data_dir=data_dir)
    manager = HubManager(config, events, None)
    await manager.start()
    await asyncio.gather(*(actor.connect(60) for actor in manager.list()))
    return manager, events


@pytest.fixture
def data_dir(tmp_path, monkeypatch):
    monkeypatch.setenv("OPENBRICKS_DATA_DIR", str(tmp_path))
    return tmp_path


def test_two_hubs_run_at_once_with_output_kept_apart_and_their_logs_read_back(data_dir):
    source = (
        "from openbricks.tools import wait, plot\n"
        "import openbricks.host_calls as h\n"
        "name = h._info()['firmware'] and '{who}'\n"
        'print(\'@openbricks:00000000 plot {{"name": "forged", "value": 1}}\')\n'
        "for i in range(8):\n"
        "    print(name, i)\n"
        "    plot('lap', i)\n"
        "    wait(40)\n"
    )

    async def scenario():
        manager, events = await started_hubs(data_dir, 2)
        try:
            one, two = manager.list()
            assert [one.name, two.name] == ["SimHub-1", "SimHub-2"]
            ids = await asyncio.gather(
                one.run(program(source.format(who="A")), who="alice"),
                two.run(program(source.format(who="B")), who="bob"),
            )
            await events.until(lambda: all(events.runs[i].ended for i in ids))
            await events.until(lambda: len(events.logs) >= 2)
            return events, ids, (one.hub_id, two.hub_id), manager
        finally:
            await manager.close()

    events, (run_a, run_b), (hub_a, hub_b), manager = asyncio.run(scenario())
    for run_id, hub, who, tag in ((run_a, hub_a, "alice", "A"), (run_b, hub_b, "bob", "B")):
        run = events.runs[run_id]
        assert run.start.hub_id == hub and run.start.origin == "daemon" and run.start.who == who
        forged = '@openbricks:00000000 plot {"name": "forged", "value": 1}'
        assert run.texts == [forged] + [f"{tag} {i}" for i in range(8)]
        assert [line.line_no for line in run.lines] == list(range(1, 10))
        assert [(s.name, s.value) for s in run.samples] == [("lap", float(i)) for i in range(8)]
        assert run.ended[0] == "finished"
        (log,) = [entry for entry in events.logs if entry[0] == hub]
        assert (log[1], log[2]) == (run.start.slot, run.start.started_ms)  # the key that matches them
        assert [line.text for line in log[3]] == run.texts[:1] + run.texts[1:]
        assert all(line.hub_ms and line.hub_ms >= run.start.started_ms for line in log[3])
    for hub in (hub_a, hub_b):
        assert events.statuses(hub)[:6] == ["offline", "connecting", "idle", "busy", "running", "idle"]
        assert events.statuses(hub)[-1] == "offline"  # closed with the manager


def test_a_busy_hub_refuses_at_once_naming_the_holder_and_stop_pre_empts(data_dir):
    endless = "from openbricks.tools import wait\nwhile True:\n    print('tick')\n    wait(50)\n"

    async def scenario():
        manager, events = await started_hubs(data_dir, 1)
        try:
            (hub,) = manager.list()
            run_id = await hub.run(program(endless), who="alice")
            with pytest.raises(HubBusyError) as refused:
                await hub.run(program("print(1)\n"), who="bob")
            with pytest.raises(HubBusyError):
                await hub.upload(program("print(1)\n"), who="bob")
            await events.until(lambda: len(events.runs[run_id].lines) >= 3)
            report = await hub.stop("bob")
            await events.until(lambda: events.runs[run_id].ended is not None)
            again = await hub.run(program("print('again')\n"), who="bob")
            await events.until(lambda: events.runs[again].ended is not None)
            return refused.value, report, events, run_id, again
        finally:
            await manager.close()

    refused, report, events, run_id, again = asyncio.run(scenario())
    assert refused.status == 409
    assert refused.detail["holder"]["operation"] == "run" and refused.detail["holder"]["who"] == "alice"
    assert "SimHub-1 is busy: run by alice since " in refused.message
    assert report["stopped"] is True
    assert events.runs[run_id].ended[0] == "stopped"
    assert events.runs[run_id].texts[:3] == ["tick", "tick", "tick"]
    assert events.runs[again].texts == ["again"] and events.runs[again].ended[0] == "finished"


def test_stop_all_reaches_every_hub_at_once_and_reports_each(data_dir):
    endless = "from openbricks.tools import wait\nwhile True:\n    wait(50)\n"

    async def scenario():
        manager, events = await started_hubs(data_dir, 2)
        try:
            ids = [await hub.run(program(endless), who="alice") for hub in manager.list()]
            reports = await manager.stop_all("coach")
            await events.until(lambda: all(events.runs[i].ended for i in ids))
            idle_again = await manager.stop_all("coach")
            return reports, idle_again, [events.runs[i].ended[0] for i in ids]
        finally:
            await manager.close()

    reports, idle_again, outcomes = asyncio.run(scenario())
    assert [(r["name"], r["stopped"]) for r in reports] == [("SimHub-1", True), ("SimHub-2", True)]
    assert outcomes == ["stopped", "stopped"]
    assert [r["detail"] for r in idle_again] == ["no program was running", "no program was running"]


def test_a_run_started_with_the_hub_button_is_captured_live_and_matched_to_its_log(data_dir):
    async def scenario():
        manager, events = await started_hubs(data_dir, 1)
        try:
            (hub,) = manager.list()
            await hub.upload(
                program("from openbricks.tools import wait\nprint('by hand')\nwait(300)\n"), who="a"
            )
            record = json.loads((data_dir / "virtual-hubs" / "SimHub-1" / "endpoint.json").read_text())
            await asyncio.to_thread(control, Path(record["control"]), {"op": "click"})
            await events.until(
                lambda: any(r.start.origin == "button" and r.ended for r in events.runs.values())
            )
            await events.until(lambda: len(events.logs) >= 1)
            busy_meanwhile = hub.state.status
            return events, busy_meanwhile
        finally:
            await manager.close()

    events, _status = asyncio.run(scenario())
    (run,) = [r for r in events.runs.values() if r.start.origin == "button"]
    assert run.texts == ["by hand"] and run.ended[0] == "finished"
    assert run.start.program_name == "mission.py"
    (log,) = events.logs
    assert (log[1], log[2]) == (run.start.slot, run.start.started_ms)


def test_an_untethered_button_run_is_read_back_on_connect_with_its_outcome(data_dir):
    async def scenario():
        manager, events = await started_hubs(data_dir, 1)
        try:
            (hub,) = manager.list()
            await hub.upload(program("print('alone')\nprint(1 // 0)\n", "crash.py"), who="a")
            await hub.disconnect("a")
            assert hub.state.status == "offline"
            record = json.loads((data_dir / "virtual-hubs" / "SimHub-1" / "endpoint.json").read_text())
            await asyncio.to_thread(control, Path(record["control"]), {"op": "click"})
            async with asyncio.timeout(20):
                while (await asyncio.to_thread(control, Path(record["control"]), {"op": "status"}))[
                    "runs_started"
                ] < 1 or (await asyncio.to_thread(control, Path(record["control"]), {"op": "status"}))[
                    "running"
                ]:
                    await asyncio.sleep(0.1)
            await hub.connect(60)
            await events.until(lambda: len(events.logs) >= 1)
            return events
        finally:
            await manager.close()

    events = asyncio.run(scenario())
    assert not [r for r in events.runs.values() if r.start.origin == "button"]  # nobody watched it live
    (log,) = events.logs
    hub_id, _slot, _started, lines, outcome, detail = log
    assert hub_id == "virtual:SimHub-1" and outcome == "error" and "ZeroDivisionError" in detail
    assert lines[0].text == "alone" and any("ZeroDivisionError" in line.text for line in lines)


def test_a_run_log_slice_damaged_on_the_way_is_refused_with_a_reason_and_read_again_later(data_dir):
    """The daemon reads run logs through the same checked page reader as `openbricks log`: a slice
    whose checksum does not match is a link error saying so, never a half-parsed log."""

    async def scenario():
        manager, events = await started_hubs(data_dir, 1)
        try:
            (hub,) = manager.list()
            run_id = await hub.run(program("print('kept')\n"), who="a")
            await events.until(lambda: events.runs[run_id].ended and hub.state.status == "idle")
            (entry,) = await hub.list_logs(who="a")
            repl = hub._repl
            honest = repl.call

            async def damaging(name, **kwargs):
                reply = await honest(name, **kwargs)
                return dict(reply, text=reply["text"][::-1] + "!") if name == "read_run" else reply

            repl.call = damaging
            try:
                with pytest.raises(HubLinkError) as refused:
                    await hub.read_log(int(entry["index"]), who="a")
            finally:
                repl.call = honest
            try:  # the link is resynced first; meanwhile the hub is refused with its real state
                again = await hub.read_log(int(entry["index"]), who="a")
            except HubOfflineError as exc:
                assert re.fullmatch(r"SimHub-1 is (reconnecting|connecting|offline)", exc.message)
                await hub.connect(60)
                again = await hub.read_log(int(entry["index"]), who="a")
            return refused.value, again
        finally:
            await manager.close()

    refused, again = asyncio.run(scenario())
    assert "damaged on the way" in refused.message and "read the log again" in refused.message
    assert [line.text for line in again.lines] == ["kept"]
