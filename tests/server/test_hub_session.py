"""Link failures reach the person at the terminal as one line that says what to do, never a traceback."""

from openbricks_server.hub_session import translate
from openbricks_server.link import HubCallError, HubException, LinkTimeout

HEAD = 'Traceback (most recent call last):\r\n  File "<stdin>", line 1, in <module>\r\n'


def test_an_old_firmware_without_a_host_call_is_told_to_update_in_one_line():
    exc = HubException("RobotA", HEAD + "AttributeError: 'module' object has no attribute 'read_file'\r\n")
    message = str(translate("RobotA", exc))
    assert message == (
        "RobotA raised AttributeError: 'module' object has no attribute 'read_file': its firmware lacks "
        "host calls this openbricks uses; update it with `openbricks flash`"
    )
    missing = HubException("RobotA", HEAD + "ImportError: no module named 'openbricks.host_calls'\r\n")
    assert "update it with `openbricks flash`" in str(translate("RobotA", missing))


def test_a_hub_out_of_memory_is_told_how_to_recover_without_its_traceback():
    exc = HubException("RobotA", HEAD + "MemoryError: memory allocation failed, allocating 16400 bytes\r\n")
    message = str(translate("RobotA", exc))
    assert "Traceback" not in message and "\n" not in message
    assert (
        "RobotA ran out of memory (MemoryError: memory allocation failed, allocating 16400 bytes)" in message
    )
    assert "press its RESET button" in message


def test_call_failures_and_timeouts_keep_their_specific_messages():
    refused = HubCallError("RobotA", "read_file", "OSError", "no file /x.py on the hub: check the path")
    assert str(translate("RobotA", refused)) == "RobotA: no file /x.py on the hub: check the path"
    silent = LinkTimeout("the raw REPL banner", "RobotA", 10)
    assert str(translate("RobotA", silent)) == (
        "RobotA stopped answering: waiting for the raw REPL banner from RobotA after 10 s; "
        "check that it is powered and in range, then retry"
    )
