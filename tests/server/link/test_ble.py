"""The BLE link through bleak's real BleakClient / BleakScanner and bleak-retry-connector, with an
emulated radio backend that enforces the MTU, paces connection events, orders notifications and
drops links on demand (tests/server/link/fake_ble_backend.py)."""

import asyncio
import os

import pytest
from bleak import BleakClient
from bleak.exc import BleakError

from openbricks_server.link import HubNotFound, LinkDropped
from openbricks_server.link.ble import NUS_RX_UUID, BleLink, find_hub, scan
from openbricks_server.link.raw_repl import RawRepl
from tests.server.link.fake_ble_backend import HubBench, LinkTiming
from tests.server.link.scripted_hub import ScriptedHub


def run(coro, timeout_s=60):
    async def bounded():
        async with asyncio.timeout(timeout_s):
            return await coro

    return asyncio.run(bounded())


def ble_link(bench, name, **kwargs):
    return BleLink(
        name,
        client_backend=bench.radio.client_backend,
        scanner_backend=bench.radio.scanner_backend,
        scan_timeout_s=kwargs.pop("scan_timeout_s", 1.0),
        **kwargs,
    )


async def ble_session(bench, name, timeout_s=5):
    link = ble_link(bench, name)
    await link.connect()
    repl = RawRepl(link, timeout_s=timeout_s)
    await repl.enter()
    return link, repl


def test_scan_lists_nus_hubs_strongest_first():
    bench = HubBench()
    bench.add("Far", rssi=-88)
    bench.add("Near", rssi=-41)
    bench.add("Middle", rssi=-63)
    bench.radio.add_hub(ScriptedHub("Headphones"), rssi=-30, advertises_nus=False)

    hubs = run(scan(0.3, scanner_backend=bench.radio.scanner_backend))

    assert [(hub.name, hub.rssi) for hub in hubs] == [("Near", -41), ("Middle", -63), ("Far", -88)]


def test_an_unknown_name_is_not_found_and_the_error_lists_the_hubs_seen():
    bench = HubBench()
    bench.add("RobotA", rssi=-50)
    with pytest.raises(HubNotFound, match=r"no hub named 'RobotZ' .*hubs seen: RobotA \(-50 dBm\)"):
        run(find_hub("RobotZ", 0.3, scanner_backend=bench.radio.scanner_backend))


def test_connect_by_name_survives_transient_connection_failures():
    bench = HubBench()
    hub = bench.add("RobotA")
    hub.refuse_connections = 2  # aborted twice, as busy radios do; bleak-retry-connector retries

    async def scenario():
        link, repl = await ble_session(bench, "RobotA")
        assert (await repl.exec("print('up')")).stdout == b"up\r\n"
        await link.close()

    run(scenario())
    assert hub.connections == 1 and hub.refuse_connections == 0


def test_writes_are_cut_to_the_mtu_and_oversize_writes_are_refused():
    bench = HubBench()
    hub = bench.add("RobotA", stdin_buffer_max=4096)

    async def scenario():
        link, repl = await ble_session(bench, "RobotA")
        assert link.write_size == 244
        data = os.urandom(12_000)
        await repl.put("/program.mpy", data, compress=False)
        assert hub.hub.files["/program.mpy"] == data
        # the emulated air itself refuses what does not fit a packet, through bleak's own client
        client = BleakClient(hub.address, backend=bench.radio.client_backend)
        await link.close()
        await client.connect()
        with pytest.raises(BleakError, match="245 bytes exceeds the 244-byte limit at MTU 247"):
            await client.write_gatt_char(NUS_RX_UUID, b"x" * 245, response=False)
        await client.disconnect()

    run(scenario())
    assert hub.stats.largest_write == 244
    assert hub.stats.refused_writes == 1
    assert hub.hub.overflow_bytes == 0


def test_output_arrives_complete_and_in_order_across_many_notifications():
    bench = HubBench()
    hub = bench.add("RobotA", timing=LinkTiming(packets_per_interval=2))

    async def scenario():
        _, repl = await ble_session(bench, "RobotA")
        # paced as a real program prints: the hub's BLE bridge keeps only the newest 4 KB it could not send
        await repl.put("/program.py", b"for i in range(400):\n    print('line %04d' % i)\n    sleep_ms(1)\n")
        chunks = []
        result = await repl.run("/program.py", on_output=chunks.append)
        return result, b"".join(chunks)

    result, output = run(scenario())
    assert result["outcome"] == "finished"
    assert output == b"".join(b"line %04d\r\n" % i for i in range(400))
    assert hub.stats.notifications > 20  # it really crossed as many MTU-sized notifications


def test_a_link_dropped_mid_paste_fails_the_upload_clearly_and_the_old_program_stays():
    bench = HubBench()
    hub = bench.add("RobotA", stdin_buffer_max=4096)

    async def scenario():
        link, repl = await ble_session(bench, "RobotA")
        old = b"print('old program')\n"
        await repl.put("/program.py", old)
        hub.drop_after_host_bytes = 6000
        with pytest.raises(LinkDropped) as caught:
            await repl.put("/program.py", os.urandom(20_000), compress=False)
        message = str(caught.value)
        assert "link to RobotA dropped while uploading /program.py (20000 bytes)" in message
        # the hub is reachable again and still holds the previous program, intact
        await link.reconnect()
        await repl.enter()
        assert await repl.get("/program.py") == old

    run(scenario())
    assert hub.connections == 2


def test_a_link_dropped_mid_run_is_reported_within_2_s_reconnected_and_no_output_is_lost():
    bench = HubBench()
    hub = bench.add("RobotA", timing=LinkTiming(supervision_timeout_ms=400))

    async def scenario():
        loop = asyncio.get_running_loop()
        _, repl = await ble_session(bench, "RobotA")
        await repl.put("/program.py", b"for i in range(120):\n    print('step', i)\n    sleep_ms(20)\n")
        events = []
        chunks = []

        def on_event(event):
            events.append((event.kind, loop.time()))

        running = asyncio.create_task(
            repl.run("/program.py", on_output=chunks.append, on_link_event=on_event, timeout_s=30)
        )
        await asyncio.sleep(0.8)
        dropped_at = loop.time()
        hub.drop()
        result = await running
        return result, b"".join(chunks), events, dropped_at

    result, output, events, dropped_at = run(scenario())
    assert [kind for kind, _ in events] == ["dropped", "reconnected"]
    assert events[0][1] - dropped_at < 2.0
    assert result["outcome"] == "finished"
    assert output == b"".join(b"step %d\r\n" % i for i in range(120))
    assert hub.connections == 2


def test_four_hubs_upload_at_once_without_sharing_state():
    bench = HubBench()
    for name in ("RobotA", "RobotB", "RobotC", "RobotD"):
        bench.add(name, stdin_buffer_max=4096)
    programs = {name: os.urandom(8000) for name in bench.peripherals}

    async def upload(name):
        link, repl = await ble_session(bench, name)
        await repl.info()
        await repl.put("/program.mpy", programs[name])
        await link.close()

    async def scenario():
        await asyncio.gather(*(upload(name) for name in programs))

    run(scenario())
    for name, peripheral in bench.peripherals.items():
        assert peripheral.hub.files["/program.mpy"] == programs[name]
