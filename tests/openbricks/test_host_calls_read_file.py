"""Reading a hub file back for the host (`get`), the paste probe and the host's reset."""

import binascii
import json

import machine

from fakes import tmpdir
from fakes.expect import raises
from openbricks import host_calls


def _write(path, data):
    with open(path, "wb") as f:
        f.write(data)


def _slices(path, size):
    """Every read_file reply for `path`, following next_offset as the host does."""
    replies = []
    offset = 0
    while offset is not None:
        reply = host_calls.read_file(path, offset, size)
        assert reply["ok"], reply
        replies.append(reply)
        offset = reply["next_offset"]
    return replies


def test_a_file_comes_back_whole_in_slices_each_with_its_own_size_and_crc():
    with tmpdir.scratch() as directory:
        path = directory + "/blob.bin"
        data = bytes(range(256)) * 11 + b"tail"
        _write(path, data)
        replies = _slices(path, 1000)
        assert [r["offset"] for r in replies] == [0, 1000, 2000]
        assert [r["bytes"] for r in replies] == [1000, 1000, len(data) - 2000]
        assert all(r["total_bytes"] == len(data) for r in replies)
        pieces = [binascii.a2b_base64(r["data"].encode()) for r in replies]
        assert b"".join(pieces) == data
        for i in range(len(replies)):
            assert replies[i]["crc32"] == binascii.crc32(pieces[i]) & 0xFFFFFFFF


def test_one_reply_never_carries_more_than_the_hub_cap_however_much_is_asked():
    with tmpdir.scratch() as directory:
        path = directory + "/big.bin"
        _write(path, b"x" * (host_calls.READ_FILE_MAX_BYTES + 10))
        first = host_calls.read_file(path, 0, 1000000)
        assert first["bytes"] == host_calls.READ_FILE_MAX_BYTES
        assert first["next_offset"] == host_calls.READ_FILE_MAX_BYTES
        last = host_calls.read_file(path, first["next_offset"])
        assert last["bytes"] == 10 and last["next_offset"] is None


def test_an_empty_file_and_an_offset_past_the_end_read_as_nothing_left():
    with tmpdir.scratch() as directory:
        path = directory + "/empty.txt"
        _write(path, b"")
        empty = host_calls.read_file(path)
        assert empty["ok"] and empty["bytes"] == 0 and empty["data"] == "" and empty["next_offset"] is None
        _write(path, b"abc")
        beyond = host_calls.read_file(path, 10)
        assert beyond["ok"] and beyond["bytes"] == 0 and beyond["next_offset"] is None


def test_a_missing_file_or_a_directory_is_refused_naming_the_path():
    with tmpdir.scratch() as directory:
        missing = host_calls.read_file(directory + "/nope.py")
        assert not missing["ok"] and missing["type"] == "OSError"
        assert "no file %s/nope.py on the hub" % directory in missing["error"]
        folder = host_calls.read_file(directory)
        assert not folder["ok"] and "is a directory, not a file" in folder["error"]


def test_bad_arguments_say_what_to_pass():
    assert "absolute file path" in host_calls.read_file("program.py")["error"]
    assert "byte offset of 0 or more" in host_calls.read_file("/program.py", -1)["error"]
    assert "1 or more" in host_calls.read_file("/program.py", 0, 0)["error"]


class _Console:
    def __init__(self):
        self.lines = []
        host_calls.print = self

    def __call__(self, *args, **kwargs):
        self.lines.append(" ".join([str(a) for a in args]))

    def close(self):
        del host_calls.print


def test_reset_replies_first_then_restarts_the_hub():
    console = _Console()
    try:
        with raises(SystemExit):  # machine.reset() never returns
            host_calls.reset()
    finally:
        console.close()
    marker = host_calls.FRAME_PREFIX + "- result "
    assert len(console.lines) == 1 and console.lines[0].startswith(marker)
    assert json.loads(console.lines[0][len(marker) :]) == {"ok": True, "resetting": True}
    assert machine.board.reset_requested


def test_paste_probe_echoes_the_token_and_counts_the_padding_that_arrived():
    reply = host_calls.paste_probe("paste-probe-512", "." * 480)
    assert reply["ok"] and reply["token"] == "paste-probe-512" and reply["padding_bytes"] == 480
    assert "must be text" in host_calls.paste_probe("t", 5)["error"]
