"""Host-call encoding (data only, never code) and result lines picked out of streamed output."""

import base64

import pytest

from openbricks_server.link import HubCallError, ProtocolError
from openbricks_server.link.host_call import (
    ResultLines,
    call_source,
    check_reply,
    python_literal,
    single_result,
)


def test_result_lines_are_found_across_chunk_boundaries():
    shown = []
    lines = ResultLines(shown.append)
    for piece in (b"@open", b"bricks-res", b'ult {"ok": true, "n": 1}\r\n', b"@ not a result\r\n"):
        lines.feed(piece)
    lines.finish()
    assert lines.results == [{"ok": True, "n": 1}]
    assert b"".join(shown) == b"@ not a result\r\n"


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


def test_an_unreadable_result_line_is_a_protocol_error_naming_it():
    lines = ResultLines(None)
    with pytest.raises(ProtocolError, match="unreadable host-call result line '{oops'"):
        lines.feed(b"@openbricks-result {oops\r\n")
