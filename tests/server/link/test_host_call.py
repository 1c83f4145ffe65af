"""Host-call encoding (data only, never code) and result frames picked out of streamed output,
whatever the program printed."""

import base64
import json

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from openbricks_server.link import HubCallError, ProtocolError
from openbricks_server.link.host_call import (
    FRAME_PREFIX,
    CallOutput,
    call_source,
    check_reply,
    command,
    python_literal,
    single_result,
)

TAG = "9f2c41d0"
START = FRAME_PREFIX + TAG.encode() + b" "
STDERR = b"Traceback (most recent call last):\r\nKeyboardInterrupt: \r\n"


def frame(kind: str, payload: bytes = b"", again: bool = False) -> bytes:
    """A frame as the hub's cooked stdout carries it."""
    return (
        START + (b"again " if again else b"") + kind.encode() + (b" " + payload if payload else b"") + b"\r\n"
    )


def feed_all(output: CallOutput, stream: bytes, cuts: list[int]) -> bytes | None:
    """Feed `stream` split at `cuts`; returns what came after the end of stdout."""
    rest = None
    edges = [0, *sorted(c for c in cuts if 0 < c < len(stream)), len(stream)]
    for a, b in zip(edges, edges[1:], strict=False):
        if output.ended:
            rest += stream[a:b]
        else:
            got = output.feed(stream[a:b])
            if got is not None:
                rest = got
    return rest


def test_result_frames_are_found_across_chunk_boundaries_and_anywhere_in_a_line():
    shown = []
    output = CallOutput(TAG, shown.append)
    for piece in (b"x", START[:5], START[5:], b'result {"ok": true, "n": 1}\r', b"\n", b"\x04", b"\x04>"):
        output.feed(piece) if not output.ended else None
    assert output.results == [{"ok": True, "n": 1}]
    assert b"".join(shown) == b"x"  # a last line without a newline is the program's, verbatim


def test_a_result_line_printed_by_the_program_is_shown_not_swallowed():
    shown = []
    output = CallOutput(TAG, shown.append)
    printed = b'@openbricks-result {"ok": true}\r\n@openbricks:00000000 result {"ok": true}\r\n'
    rest = output.feed(
        frame("program") + printed + frame("result", b'{"ok": true, "outcome": "finished"}') + b"\x04\x04>"
    )
    assert b"".join(shown) == printed and rest == b"\x04>"
    assert output.results == [{"ok": True, "outcome": "finished"}]


def test_a_ctrl_d_the_program_prints_is_output_until_the_result_frame():
    output = CallOutput(TAG, None)
    rest = output.feed(
        frame("program") + b"a\x04b\x04>" + frame("result", b'{"ok": true}') + b"\x04" + STDERR + b"\x04>"
    )
    assert bytes(output.output) == b"a\x04b\x04>" and rest == STDERR + b"\x04>"


def test_untagged_code_has_no_frames_and_ends_at_the_first_ctrl_d():
    output = CallOutput(None, None)
    assert output.feed(frame("result", b"{}") + b"\x04err\x04>") == b"err\x04>"
    assert bytes(output.output) == frame("result", b"{}") and output.results == []


def test_each_command_gets_a_fresh_tag_it_hands_the_hub_first():
    one, two = (
        command(("info", {})),
        command(("stage_begin", {"path": "/p.py"}), ("stage_append", {"payload": "QQ=="})),
    )
    assert one.tag != two.tag and len(one.tag) == 8
    assert one.source == f"import openbricks.host_calls as h;h.tag({one.tag!r});h.info()"
    assert two.source.splitlines()[1] == "h.stage_append(payload='QQ==')"


def _printed():
    """Program output that tries everything: any bytes, Ctrl-D, frames with other tags and none,
    the old result marker, and proper prefixes of the real frame start."""
    piece = st.one_of(
        st.binary(max_size=40),
        st.sampled_from([b"\x04", b"\r\n", b"\x03", b"\xff\xfe", b"\x04>", b"\x01"]),
        st.builds(lambda k: START[:k], st.integers(1, len(START) - 1)),
        st.builds(
            lambda other, body: FRAME_PREFIX + other.encode() + b" result " + body + b"\r\n",
            st.text("0123456789abcdef", min_size=0, max_size=8).filter(lambda t: t != TAG),
            st.binary(max_size=20),
        ),
        st.just(b'@openbricks-result {"ok": true, "outcome": "finished", "run": 0}\r\n'),
        st.just(FRAME_PREFIX + b"- result {}\r\n"),
    )
    return st.lists(piece, max_size=12).map(b"".join)


@settings(max_examples=400, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(
    printed=_printed(),
    reply=st.dictionaries(st.text(max_size=6), st.one_of(st.integers(), st.text(max_size=10)), max_size=3),
    cut_program=st.one_of(st.none(), st.integers(0, 40)),
    cut_result=st.one_of(st.none(), st.integers(0, 60)),
    stopped=st.booleans(),
    cuts=st.lists(st.integers(0, 400), max_size=12),
)
def test_the_program_output_comes_out_verbatim_and_the_result_exactly_once(
    printed, reply, cut_program, cut_result, stopped, cuts
):
    """However the program's output looks and however the stream is split, the host shows exactly
    what the program printed and gets the hub's result; a frame the hub had to write again after a
    Ctrl-C cut it (at any byte) leaves nothing behind."""
    reply = {"ok": True, **reply}
    payload = json.dumps(reply).encode()
    program, result = frame("program"), frame("result", payload)
    stream = b""
    if cut_program is not None:
        stream += program[: min(cut_program, len(program) - 1)] + frame("program", again=True)
    else:
        stream += program
    stream += printed
    if cut_result is not None:
        stream += result[: min(cut_result, len(result) - 1)] + frame("result", payload, again=True)
    else:
        stream += result
    stderr = STDERR if stopped else b""
    stream += b"\x04" + stderr + b"\x04>"
    expected = printed
    if cut_result == 0:
        # A frame cut before its first byte went out: output ending in the first bytes of the real
        # frame start (which carries the tag, so only by chance) cannot be told from a cut frame.
        expected = printed[: len(printed) - _tail(printed)]
    shown = []
    output = CallOutput(TAG, shown.append)
    rest = feed_all(output, stream, cuts)
    assert output.ended and rest == stderr + b"\x04>"
    assert b"".join(shown) == bytes(output.output) == expected
    assert output.results == [reply]


def _tail(data: bytes) -> int:
    for n in range(min(len(START) - 1, len(data)), 0, -1):
        if data.endswith(START[:n]):
            return n
    return 0


def test_host_call_arguments_are_data_only():
    assert call_source("stage", {"payload": "QUJD", "size": 3, "compression": None}) == (
        "import openbricks.host_calls as h;h.stage(payload='QUJD', size=3, compression=None)"
    )
    assert python_literal({"a": [1, 2.5, True]}) == "{'a': [1, 2.5, True]}"
    with pytest.raises(ValueError, match="only finite numbers"):
        python_literal(float("nan"))
    with pytest.raises(ValueError, match="cannot be sent to the hub as data"):
        python_literal(object())
    with pytest.raises(ValueError, match="not a Python identifier"):
        call_source("info(); import os", {})
    # quotes and control characters in data stay inside the literal
    tricky = "it's \x04 \x03 done"
    assert eval(python_literal(tricky)) == tricky  # noqa: S307 - checking the literal round-trips
    assert base64.b64decode(eval(python_literal(base64.b64encode(b"\x00\xff").decode()))) == b"\x00\xff"  # noqa: S307


def test_a_failed_reply_raises_with_the_hubs_reason_and_a_silent_call_says_what_is_missing():
    with pytest.raises(HubCallError, match=r"read_file on RobotA failed \(OSError\): no file /x on the hub"):
        check_reply("RobotA", "read_file", {"ok": False, "type": "OSError", "error": "no file /x on the hub"})
    with pytest.raises(ProtocolError, match="info on RobotA printed no result line .*'Traceback"):
        single_result("RobotA", "info", [], b"Traceback (most recent call last)")


def test_an_unreadable_result_frame_is_a_protocol_error_naming_it():
    output = CallOutput(TAG, None)
    with pytest.raises(ProtocolError, match="unreadable host-call result '{oops'"):
        output.feed(frame("result", b"{oops"))
