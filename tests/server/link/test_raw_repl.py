"""The raw-REPL client against an emulated hub that speaks MicroPython's REPL byte for byte."""

import asyncio
import os
import re
import zlib

import pytest

from openbricks_server.link import HubCallError, HubException, LinkTimeout, ProtocolError
from openbricks_server.link.raw_repl import RawRepl
from tests.server.link.loopback import LoopbackLink
from tests.server.link.scripted_hub import ScriptedHub


def run(coro, timeout_s=30):
    async def bounded():
        async with asyncio.timeout(timeout_s):
            return await coro

    return asyncio.run(bounded())


async def session(hub=None, **repl_kwargs):
    hub = hub or ScriptedHub("RobotA")
    link = LoopbackLink(hub)
    await link.connect()
    repl = RawRepl(link, timeout_s=repl_kwargs.pop("timeout_s", 5), **repl_kwargs)
    await repl.enter()
    return hub, link, repl


def test_exec_returns_what_the_hub_printed():
    async def scenario():
        _, _, repl = await session()
        result = await repl.exec("print(6 * 7)")
        assert result.stdout == b"42\r\n" and result.stderr == b""

    run(scenario())


def test_an_exception_on_the_hub_raises_with_its_traceback_and_the_session_goes_on():
    async def scenario():
        _, _, repl = await session()
        with pytest.raises(HubException, match="RobotA raised ZeroDivisionError") as caught:
            await repl.exec("print('before'); 1/0")
        assert "Traceback" in caught.value.traceback
        assert caught.value.stdout == b"before\r\n"
        assert (await repl.exec("print('still here')")).stdout == b"still here\r\n"

    run(scenario())


def test_enter_recovers_a_hub_left_in_the_middle_of_a_raw_paste():
    async def scenario():
        hub, link, repl = await session()
        await link.write(b"\x05A\x01print('half")  # a previous session died mid-upload
        await asyncio.sleep(0.05)
        await repl.enter()
        assert (await repl.exec("print('fresh')")).stdout == b"fresh\r\n"
        assert not any("half" in command for command in hub.commands)

    run(scenario())


def test_enter_works_from_the_friendly_repl():
    async def scenario():
        hub = ScriptedHub("RobotA")
        link = LoopbackLink(hub)
        await link.connect()
        repl = RawRepl(link, timeout_s=2)
        await repl.enter()
        await repl.exit()
        await repl.enter()
        assert (await repl.exec("print(1)")).stdout == b"1\r\n"

    run(scenario())


def test_soft_reset_comes_back_to_a_working_raw_repl():
    async def scenario():
        _, _, repl = await session()
        await repl.soft_reset()
        assert (await repl.exec("print(2)")).stdout == b"2\r\n"

    run(scenario())


def test_raw_paste_never_sends_more_than_the_hub_granted():
    async def scenario():
        hub, _, repl = await session(ScriptedHub("RobotA", stdin_buffer_max=256))
        data = os.urandom(20_000)
        await repl.put("/program.mpy", data, compress=False)
        assert hub.files["/program.mpy"] == data
        assert repl.paste_window == 128
        assert hub.overflow_bytes == 0

    run(scenario())


def test_sending_ahead_stays_within_what_the_hubs_stdin_ring_holds():
    async def scenario():
        hub, _, repl = await session(ScriptedHub("RobotA", stdin_buffer_max=256), send_ahead=True)
        await repl.exec("print(0)")
        sources = [f"x = {'1' * 600}\nprint(len(str(x)))" for _ in range(4)]
        results = await repl.exec_many(sources)
        assert [result.stdout for result in results] == [b"600\r\n"] * 4
        assert hub.overflow_bytes == 0

    run(scenario())


def test_a_hub_without_raw_paste_gets_plain_raw_commands():
    async def scenario():
        hub, _, repl = await session(ScriptedHub("RobotA", raw_paste=False))
        assert (await repl.exec("print('plain')")).stdout == b"plain\r\n"
        await repl.put("/a.py", b"x = 1\n" * 300)
        assert hub.files["/a.py"] == b"x = 1\n" * 300
        assert repl.paste_window is None

    run(scenario())


def test_pipelined_commands_stop_at_the_first_failure_and_the_rest_never_runs():
    async def scenario():
        hub, _, repl = await session(send_ahead=True)
        await repl.exec("print(0)")  # the window is known now: later commands go out with their request
        with pytest.raises(HubException):
            await repl.exec_many(["1/0", "print('second')", "print('third')"])
        assert hub.commands[-1] == "1/0"
        assert (await repl.exec("print('after')")).stdout == b"after\r\n"

    run(scenario())


def test_host_calls_return_their_result_and_failures_raise_with_the_hubs_reason():
    async def scenario():
        _, _, repl = await session()
        info = await repl.info()
        assert info.firmware == "openbricks 2.7.1 (emulated)" and "zlib" in info.compression
        assert (await repl.set_rtc(1_700_000_000_000))["epoch_ms"] == 1_700_000_000_000
        with pytest.raises(
            HubCallError, match=r"stage_append on RobotA failed \(RuntimeError\): no upload in progress"
        ):
            await repl.call("stage_append", payload="AAAA")

    run(scenario())


def test_put_compresses_when_the_hub_can_inflate_and_verifies_the_result():
    async def scenario():
        hub, _, repl = await session()
        await repl.info()
        source = b"from openbricks.robotics import DriveBase\n" + b"robot.straight(100)\n" * 400
        result = await repl.put("/program.py", source)
        assert hub.files["/program.py"] == source
        assert result["bytes"] == len(source) and result["crc32"] == zlib.crc32(source)
        stage = next(command for command in hub.commands if "h.stage(" in command)
        assert "compression='zlib'" in stage
        assert len(stage) < len(source) / 4  # repetitive source: the wire carries a fraction of it

    run(scenario())


def test_put_sends_incompressible_data_as_is():
    async def scenario():
        hub, _, repl = await session()
        await repl.info()
        data = os.urandom(3000)
        await repl.put("/blob.bin", data)
        assert hub.files["/blob.bin"] == data
        assert "compression=None" in hub.commands[-1]

    run(scenario())


def test_put_chunks_a_large_file_into_staged_appends():
    async def scenario():
        hub, _, repl = await session(ScriptedHub("RobotA", compression=()))
        data = os.urandom(30_000)
        await repl.put("/program.mpy", data, call_payload_chars=8192)
        assert hub.files["/program.mpy"] == data
        assert "stage_begin" in hub.commands[-5] and "stage_end" in hub.commands[-1]
        assert sum("stage_append" in command for command in hub.commands) == 5

    run(scenario())


def test_a_failed_chunk_stops_the_upload_with_the_hubs_reason():
    async def scenario():
        hub, _, repl = await session(ScriptedHub("RobotA", compression=()))
        hub.call_failures["stage_append"] = ValueError(
            "program is larger than the hub accepts (4096 bytes max)"
        )
        with pytest.raises(HubCallError, match="larger than the hub accepts"):
            await repl.put("/program.mpy", os.urandom(30_000), call_payload_chars=8192)
        assert sum("stage_append" in command for command in hub.commands) == 1
        assert "/program.mpy" not in hub.files

    run(scenario())


def test_run_streams_program_output_and_keeps_the_result_line_out_of_it():
    async def scenario():
        _, _, repl = await session()
        await repl.put("/program.py", b"for i in range(4):\n    print('lap', i)\n    sleep_ms(20)\n")
        chunks = []
        result = await repl.run("/program.py", on_output=chunks.append)
        assert result["outcome"] == "finished"
        assert b"".join(chunks) == b"lap 0\r\nlap 1\r\nlap 2\r\nlap 3\r\n"
        assert len(chunks) >= 2  # it arrived as the program printed, not in one piece at the end

    run(scenario())


def test_ctrl_c_stops_a_run_and_the_stop_is_an_outcome():
    async def scenario():
        _, _, repl = await session()
        await repl.put("/program.py", b"while True:\n    print('tick')\n    sleep_ms(10)\n")
        running = asyncio.create_task(repl.run("/program.py"))
        await asyncio.sleep(0.1)
        await repl.interrupt()
        result = await running
        assert result["outcome"] == "stopped"
        assert (await repl.exec("print('ok')")).stdout == b"ok\r\n"

    run(scenario())


def test_a_ctrl_c_asked_for_while_the_command_is_sent_waits_until_the_hub_has_all_of_it():
    """Sent mid-paste, the Ctrl-C would end the paste and the rest of the command would run later
    anyway, out of the host's sight (the next command then met a running program)."""

    async def scenario():
        hub, _, repl = await session()
        await repl.put("/program.py", b"while True:\n    sleep_ms(10)\n")
        running = asyncio.create_task(repl.run("/program.py"))
        await asyncio.sleep(0)  # the run command is being pasted now
        await repl.interrupt()
        try:
            result = await running
            assert result["outcome"] == "stopped"
        except HubException as exc:  # stopped before the program started: also a stop
            assert "KeyboardInterrupt" in exc.summary
        assert not hub.busy
        assert (await repl.exec("print('ok')")).stdout == b"ok\r\n"

    run(scenario())


def test_get_reads_back_a_file_through_read_file_calls_with_data_only():
    async def scenario():
        hub, _, repl = await session()
        hub.files["/data.bin"] = os.urandom(9000)
        before = len(hub.commands)
        assert await repl.get("/data.bin", block_bytes=2048) == hub.files["/data.bin"]
        sent = hub.commands[before:]
        assert len(sent) == 5  # 9000 bytes in 2048-byte slices
        assert all(
            re.match(
                r"import openbricks.host_calls as h;h.tag\('[0-9a-f]{8}'\);h.read_file\(path='/data.bin'", c
            )
            for c in sent
        )
        assert "offset=8192, size=2048" in sent[-1]

    run(scenario())


def test_get_follows_the_hubs_own_slice_cap_and_reads_empty_files():
    async def scenario():
        hub, _, repl = await session()
        hub.read_cap_bytes = 1000
        hub.files["/log.txt"] = b"line\n" * 700
        hub.files["/empty"] = b""
        assert await repl.get("/log.txt") == hub.files["/log.txt"]
        assert await repl.get("/empty") == b""

    run(scenario())


def test_get_names_a_missing_file_and_refuses_a_damaged_slice():
    async def scenario():
        hub, _, repl = await session()
        with pytest.raises(
            HubCallError, match="read_file on RobotA failed \\(OSError\\): no file /nope on the hub"
        ):
            await repl.get("/nope")
        hub.files["/data.bin"] = bytes(6000)
        hub.corrupt_read = lambda data: data[:-1] + b"\x01" if len(data) < 4096 else data
        with pytest.raises(ProtocolError, match="/data.bin from RobotA arrived damaged at offset 4096"):
            await repl.get("/data.bin")
        assert (await repl.exec("print('ok')")).stdout == b"ok\r\n"  # the session goes on

    run(scenario())


def test_reset_hub_returns_the_hubs_confirmation_and_the_restarted_hub_takes_a_new_session():
    async def scenario():
        hub, _, repl = await session()
        assert await repl.reset_hub() == {"ok": True, "resetting": True}
        assert re.fullmatch(
            r"import openbricks.host_calls as h;h.tag\('[0-9a-f]{8}'\);h.reset\(\)", hub.commands[-1]
        )
        await asyncio.sleep(0.05)
        assert hub.resets == 1
        await repl.enter()
        assert (await repl.exec("print('back')")).stdout == b"back\r\n"

    run(scenario())


def test_reset_hub_on_firmware_without_the_call_raises_the_hubs_error_and_the_session_goes_on():
    async def scenario():
        hub, _, repl = await session()
        hub.missing_calls.add("reset")
        with pytest.raises(HubException, match="AttributeError: 'module' object has no attribute 'reset'"):
            await repl.reset_hub(timeout_s=2)
        assert hub.resets == 0
        assert (await repl.exec("print('still')")).stdout == b"still\r\n"

    run(scenario())


def test_a_hub_that_never_answers_times_out_naming_the_wait():
    async def scenario():
        hub = ScriptedHub("RobotA")
        link = LoopbackLink(hub)
        await link.connect()
        hub.feed = lambda data: None  # a hub that hears nothing
        with pytest.raises(LinkTimeout, match="waiting for the raw REPL banner from RobotA after 0.1 s"):
            await RawRepl(link, timeout_s=0.1).enter()

    run(scenario())


def test_garbage_during_a_paste_is_a_protocol_error():
    async def scenario():
        hub, link, repl = await session()
        await repl.exec("print(0)")
        send = hub._send

        def noisy_grant(data):
            send(data + b"?" if data.startswith(b"R\x01") else data)  # a stray byte after the grant

        hub._send = noisy_grant
        with pytest.raises(ProtocolError, match="RobotA sent b'\\?' during a raw-paste upload"):
            await repl.put("/x.bin", os.urandom(2000), compress=False)

    run(scenario())
