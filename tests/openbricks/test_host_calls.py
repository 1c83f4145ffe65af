"""The host's operations on the hub: one JSON result line each, staged files verified and atomic,
runs streamed and logged, logs paged, the RTC set (servo scans and re-IDs: test_host_calls_servos.py)."""

import binascii
import json
import sys

import openbricks
from fakes import tmpdir
from fakes.expect import raises
from openbricks import host_calls, launcher, log

# zlib stream of a 1664-byte program (41 lines), made on the host; crc32 of the inflated program.
ZLIB_PROGRAM_B64 = (
    "eNqN1LsOwjAMRuGdp7CYYEHY5vo4paQooq2jJBKvz8yCzn4mf/o91VgkSlofNY/vdugRc5O8lKhdPkPum1Lz2nfbOa9JjhKTDD"
    "LGUmpqLT2l1HjVYdnufzqFncHOYXeC3Rl2F9hdYXeD3Z3eGYNQEaUkSk2UoihVUcqi1EUpjFIZozKGt0JljMoYlTEqY1TGqIxR"
    "GaMyTmWcyjh+Y1TGqYxTGacyTmWcyvg/mS9t3TXETrY="
)
ZLIB_PROGRAM_BYTES = 1664
ZLIB_PROGRAM_CRC32 = 3278701590


class _Console:
    """Collects what host_calls prints, as the host would read it off the raw REPL."""

    def __init__(self):
        self.lines = []
        host_calls.print = self  # the module's print now lands here

    def __call__(self, *args, **kwargs):
        self.lines.append(" ".join([str(a) for a in args]))

    def results(self):
        marker = host_calls.FRAME_PREFIX + "- result "
        return [json.loads(line[len(marker) :]) for line in self.lines if line.startswith(marker)]

    def close(self):
        del host_calls.print


def _b64(data):
    return binascii.b2a_base64(data).decode().strip()


def _read(path):
    with open(path, "rb") as f:
        return f.read()


def _exists(path):
    import os

    try:
        os.stat(path)
        return True
    except OSError:
        return False


def test_info_reports_version_capabilities_as_one_marked_json_line():
    console = _Console()
    try:
        result = host_calls.info()
    finally:
        console.close()
    assert console.results() == [result]
    assert len(console.lines) == 1
    assert result["ok"] and result["protocol"] == 2
    assert result["firmware"] == openbricks.firmware_label() == "2.7.1 (customized)"
    assert result["version"] == "2.7.1"
    assert result["accepts_mpy"] == hasattr(sys.implementation, "_mpy")
    assert result["log_slots"] == 10 and result["log_max_bytes"] == 65536
    assert result["max_program_bytes"] == host_calls.MAX_PROGRAM_BYTES
    assert result["program_path"] == "/program.mpy"
    assert result["compression"] == ["zlib"]
    assert result["running"] is False


def test_set_rtc_makes_log_stamps_real_utc_times():
    result = host_calls.set_rtc(1783950123456)
    assert result["ok"]
    assert abs(result["epoch_ms"] - 1783950123456) <= 1
    assert abs(log.epoch_ms() - 1783950123456) <= 1
    bad = host_calls.set_rtc("yesterday")
    assert not bad["ok"] and "integer Unix milliseconds" in bad["error"] and bad["type"] == "ValueError"


def test_stage_writes_the_program_atomically_and_verifies_it():
    with tmpdir.scratch() as directory:
        path = directory + "/program.mpy"
        program = b"M\x06\x00\x1f" + bytes(range(256)) * 4
        result = host_calls.stage(_b64(program), path, size=len(program), crc32=binascii.crc32(program))
        assert result["ok"] and result["bytes"] == len(program)
        assert _read(path) == program
        # A corrupted upload is refused and the good program stays in place.
        bad = host_calls.stage(_b64(b"garbage"), path, crc32=binascii.crc32(program))
        assert not bad["ok"] and "upload corrupted" in bad["error"]
        assert _read(path) == program
        assert not _exists(path + ".part")
        short = host_calls.stage(_b64(program[:100]), path, size=len(program))
        assert not short["ok"] and "upload truncated: got 100 bytes, expected 1028" in short["error"]


def test_a_compressed_program_is_inflated_and_checked_against_its_crc():
    with tmpdir.scratch() as directory:
        path = directory + "/program.py"
        result = host_calls.stage(
            ZLIB_PROGRAM_B64, path, compression="zlib", size=ZLIB_PROGRAM_BYTES, crc32=ZLIB_PROGRAM_CRC32
        )
        assert result["ok"], result
        text = _read(path).decode()
        assert text.startswith("from openbricks.tools import wait\n")
        assert text.count("\n") == 41


def test_staging_one_form_removes_the_stale_other_so_the_launcher_runs_the_new_program():
    with tmpdir.scratch() as directory:
        host_calls.stage(_b64(b"print('old source')\n"), directory + "/program.py")
        host_calls.stage(_b64(b"M\x06\x00\x1f"), directory + "/program.mpy")
        assert not _exists(directory + "/program.py")
        assert launcher.resolve_program(directory + "/program.mpy") == directory + "/program.mpy"


def test_chunked_upload_with_compression_lands_whole():
    with tmpdir.scratch() as directory:
        path = directory + "/program.py"
        compressed = binascii.a2b_base64(ZLIB_PROGRAM_B64.encode())
        assert host_calls.stage_begin(path)["ok"]
        for start in range(0, len(compressed), 64):
            assert host_calls.stage_append(_b64(compressed[start : start + 64]))["ok"]
        assert not _exists(path)  # nothing is in place until the upload is complete and verified
        done = host_calls.stage_end("zlib", ZLIB_PROGRAM_BYTES, ZLIB_PROGRAM_CRC32)
        assert done["ok"] and done["bytes"] == ZLIB_PROGRAM_BYTES
        assert _read(path).count(b"\n") == 41
        orphan = host_calls.stage_append(_b64(b"more"))
        assert not orphan["ok"] and "call stage_begin(path) first" in orphan["error"]


def test_oversized_programs_and_bad_paths_are_refused_with_the_limit():
    with tmpdir.scratch() as directory:
        big = bytes(host_calls.MAX_PROGRAM_BYTES + 1)
        result = host_calls.stage(big, directory + "/program.mpy", encoding="raw")
        assert not result["ok"] and "larger than the hub accepts (262144 bytes max)" in result["error"]
        assert not _exists(directory + "/program.mpy")
        assert "absolute file path" in host_calls.stage(_b64(b"x"), "program.py")["error"]
        assert "absolute file path" in host_calls.stage(_b64(b"x"), "/../etc/x")["error"]


def test_run_streams_the_program_output_then_the_result_line():
    with tmpdir.scratch() as directory:
        path = directory + "/program.py"
        host_calls.stage(_b64(b"print('hello from the hub')\n"), path)
        launcher.get(program_path=path, log_dir=directory + "/logs")
        console = _Console()
        try:
            host_calls.run()
        finally:
            console.close()
        sent = b"hello from the hub\r\n"  # as the console sends it: CR LF line ends
        assert console.results() == [
            {
                "ok": True,
                "outcome": "finished",
                "run": 0,
                "printed_bytes": len(sent),
                "printed_crc32": binascii.crc32(sent) & 0xFFFFFFFF,
            }
        ]
        assert "hello from the hub" in log.read_run(0, directory + "/logs")


def test_a_stopped_run_reports_then_propagates_the_interrupt():
    with tmpdir.scratch() as directory:
        path = directory + "/program.py"
        host_calls.stage(_b64(b"raise KeyboardInterrupt\n"), path)
        launcher.get(program_path=path, log_dir=directory + "/logs")
        console = _Console()
        try:
            with raises(KeyboardInterrupt):
                host_calls.run()
        finally:
            console.close()
        assert console.results() == [
            {"ok": True, "outcome": "stopped", "run": 0, "printed_bytes": 0, "printed_crc32": 0}
        ]


def test_a_result_frame_cut_by_a_ctrl_c_is_written_again_marked_then_the_stop_propagates():
    with tmpdir.scratch() as directory:
        path = directory + "/program.py"
        host_calls.stage(_b64(b"x = 1\n"), path)
        launcher.get(program_path=path, log_dir=directory + "/logs")
        console = _Console()
        cut = [True]

        def cutting(*args, **kwargs):
            if cut[0] and " result " in args[0]:
                cut[0] = False
                raise KeyboardInterrupt  # the write of the result frame was cut
            console(*args, **kwargs)

        host_calls.print = cutting
        host_calls.tag("0a1b2c3d")
        try:
            with raises(KeyboardInterrupt):
                host_calls.run()
        finally:
            host_calls.tag("-")
            console.close()
        assert len(console.lines) == 2 and console.lines[0] == "@openbricks:0a1b2c3d program\n"
        again = "@openbricks:0a1b2c3d again result "
        assert console.lines[1].startswith(again)
        reply = json.loads(console.lines[1][len(again) :])
        assert reply["outcome"] == "finished" and reply["run"] == 0


def test_info_tells_a_run_a_console_ctrl_c_stopped_since_the_last_reply_from_an_older_one():
    with tmpdir.scratch() as directory:
        path = directory + "/program.py"
        host_calls.stage(_b64(b"raise KeyboardInterrupt\n"), path)
        launcher.get(program_path=path, log_dir=directory + "/logs")
        console = _Console()
        try:
            with raises(KeyboardInterrupt):
                host_calls.run()  # a CLI killed mid-run: nobody read this reply
            first = host_calls.info()["last_run"]
            second = host_calls.info()["last_run"]
        finally:
            console.close()
        assert first == {
            "index": 0,
            "outcome": "stopped",
            "trigger": "host run",
            "stopped_by": "console",
            "since_last_call": True,
        }
        assert second["since_last_call"] is False


def test_run_without_a_staged_program_says_how_to_stage_one():
    with tmpdir.scratch() as directory:
        launcher.get(program_path=directory + "/program.mpy", log_dir=directory + "/logs")
        result = host_calls.run()
        assert not result["ok"] and "upload one with `openbricks upload` or `run`" in result["error"]


def test_logs_are_listed_and_paged_in_whole_lines():
    with tmpdir.scratch() as directory:
        log_dir = directory + "/logs"
        for n in range(2):
            with log.session(log_dir):
                for i in range(50):
                    log.write("run %d line %d with some text\n" % (n, i))
        listed = host_calls.runs(log_dir)
        assert [r["index"] for r in listed["runs"]] == [0, 1] and listed["slots"] == 10
        whole = log.read_run(1, log_dir)
        assert listed["runs"][1]["bytes"] == len(whole)
        pieces = []
        offset = 0
        while offset is not None:
            page = host_calls.read_run(1, offset, 300, log_dir)
            assert page["ok"] and page["text"].endswith("\n")
            pieces.append(page["text"])
            offset = page["next_offset"]
        assert "".join(pieces) == whole and len(pieces) > 5
        gone = host_calls.read_run(7, log_dir=log_dir)
        assert not gone["ok"] and "run 7 is not on the hub" in gone["error"]


def test_record_provenance_is_what_the_next_label_reports():
    result = host_calls.record_provenance("official")
    assert result == {"ok": True, "firmware": "2.7.1 (official)"}
    assert host_calls.info()["provenance"] == "official"
