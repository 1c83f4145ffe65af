"""The REPL protocol engine, byte for byte as MicroPython's pyexec.c answers a host."""

import struct

import pytest

from openbricks_sim.virtual_hub.repl import (
    FRIENDLY,
    PASTE,
    RAW,
    Execute,
    Interrupt,
    ReplProtocol,
    SoftReboot,
)

BANNER = b"openbricks test hub\r\n"


class Link:
    """The host's view: everything the hub wrote, taken in pieces."""

    def __init__(self):
        self.data = bytearray()

    def write(self, data):
        self.data.extend(data)

    def take(self):
        out = bytes(self.data)
        self.data.clear()
        return out


def booted(paste_window=128):
    """A hub past power-up (main.py done), at the friendly prompt."""
    link = Link()
    repl = ReplProtocol(link.write, BANNER, paste_window)
    assert repl.execution_done(None) == []
    assert link.take() == BANNER + b">>> "
    return repl, link


def raw(paste_window=128):
    repl, link = booted(paste_window)
    repl.feed(b"\x01")
    assert link.take() == b"\r\nraw REPL; CTRL-B to exit\r\n>"
    return repl, link


def test_raw_repl_runs_source_after_ctrl_d_and_frames_the_output_with_eofs():
    repl, link = raw()
    events = repl.feed(b"print(1)\x04")
    assert events == [Execute(b"print(1)", RAW)]
    assert link.take() == b"OK"
    assert repl.running == RAW
    assert repl.execution_done(None) == []
    assert link.take() == b"\x04\x04>"


def test_a_traceback_goes_between_the_two_eofs_with_crlf_newlines():
    repl, link = raw()
    repl.feed(b"1/0\x04")
    link.take()
    repl.execution_done("Traceback (most recent call last):\nZeroDivisionError: divide by zero\n")
    assert link.take() == (
        b"\x04Traceback (most recent call last):\r\nZeroDivisionError: divide by zero\r\n\x04>"
    )


def test_ctrl_d_on_an_empty_raw_line_is_a_soft_reboot_back_into_the_raw_repl():
    repl, link = raw()
    assert repl.feed(b"\x04") == [SoftReboot()]
    assert link.take() == b"OK\r\n"
    repl.execution_done(None)
    assert link.take() == b"raw REPL; CTRL-B to exit\r\n>"


def test_ctrl_c_clears_the_raw_line_and_ctrl_a_reprints_the_banner():
    repl, link = raw()
    assert repl.feed(b"garbage\x03print(2)\x04") == [Execute(b"print(2)", RAW)]
    repl.execution_done(None)
    link.take()
    repl.feed(b"half a line\x01")
    assert link.take() == b"raw REPL; CTRL-B to exit\r\n>"
    assert repl.feed(b"x=1\x04") == [Execute(b"x=1", RAW)]


def test_ctrl_b_leaves_the_raw_repl_for_the_friendly_one():
    repl, link = raw()
    repl.feed(b"\x02")
    assert link.take() == b"\r\n" + BANNER + b">>> "
    assert not repl.raw_mode


def test_raw_paste_grants_two_windows_then_one_per_window_consumed():
    repl, link = raw()
    assert repl.feed(b"\x05A\x01") == []
    assert link.take() == b"R\x01" + struct.pack("<H", 128) + b"\x01"
    source = b"x = 1\n" * 50  # 300 bytes: two windows consumed
    assert repl.feed(source[:256]) == []
    assert link.take() == b"\x01\x01"
    assert repl.feed(source[256:]) == []
    assert link.take() == b""
    assert repl.feed(b"\x04") == [Execute(source, PASTE)]
    assert link.take() == b"\x04"  # end of data acknowledged, nothing else yet
    repl.execution_done(None)
    assert link.take() == b"\x04\x04>"
    assert repl.overrun_bytes == 0


def test_the_paste_window_is_configurable_and_sent_little_endian():
    repl, link = raw(paste_window=1000)
    repl.feed(b"\x05A\x01")
    assert link.take() == b"R\x01\xe8\x03\x01"
    repl.feed(b"a" * 1000)
    assert link.take() == b"\x01"


def test_bytes_beyond_the_granted_windows_are_lost_as_on_an_overfull_hub():
    repl, link = raw(paste_window=16)
    repl.feed(b"\x05A\x01")
    link.take()
    repl.feed(b"a" * 32)  # both initial windows: fine
    assert link.take() == b"\x01\x01"
    repl.feed(b"b" * 40)  # only 32 granted since: 8 bytes overrun
    assert repl.overrun_bytes == 8
    (event,) = repl.feed(b"\x04")
    assert event.source == b"a" * 32 + b"b" * 32


def test_data_in_the_same_read_as_the_raw_paste_request_is_an_overrun():
    repl, link = raw(paste_window=16)
    repl.feed(b"\x05A\x01abc")  # sent before the host could have read the window size
    assert repl.overrun_bytes == 3


def test_a_paste_request_typed_ahead_while_code_ran_uses_its_grant_at_once():
    """Bytes that waited in the stdin ring were sent before the grant, but the ring holds them."""
    repl, link = raw(paste_window=16)
    repl.feed(b"print(0)\x04")
    repl.feed(b"\x05A\x01" + b"a" * 32)  # the next command, right behind: into the stdin ring
    assert repl.execution_done(None) == []
    assert repl.overrun_bytes == 0 and repl.receiving_paste


def test_with_its_size_given_the_stdin_ring_holds_what_a_host_sends_ahead_and_no_more():
    link = Link()
    repl = ReplProtocol(link.write, BANNER, 16, stdin_ring_bytes=36)
    repl.execution_done(None)
    repl.feed(b"\x01")
    repl.feed(b"\x05A\x01" + b"a" * 37)  # two windows and the ring's 4 spare bytes fit, not one more
    assert repl.overrun_bytes == 1
    repl.feed(b"b" * 32)  # the windows granted while those were read
    assert repl.overrun_bytes == 1
    assert repl.feed(b"\x04") == [Execute(b"a" * 36 + b"b" * 32, PASTE)]
    repl.feed(b"x" * 40)  # for the running code: the ring keeps 36 bytes of it
    assert (len(repl.stdin), repl.overrun_bytes) == (36, 5)


def test_a_firmware_without_raw_paste_refuses_it_with_r_nul():
    link = Link()
    repl = ReplProtocol(link.write, BANNER, raw_paste=False)
    repl.execution_done(None)
    repl.feed(b"\x01")
    link.take()
    repl.feed(b"\x05A\x01")
    assert link.take() == b"R\x00>"
    assert repl.feed(b"z=3\x04") == [Execute(b"z=3", RAW)]


def test_raw_paste_cancelled_with_ctrl_c_reports_keyboard_interrupt_and_returns_to_the_prompt():
    repl, link = raw()
    repl.feed(b"\x05A\x01")
    link.take()
    assert repl.feed(b"while True: pass\x03") == []
    assert link.take() == b"\x04\x04KeyboardInterrupt: \r\n\x04>"
    assert repl.running is None
    assert repl.feed(b"y=2\x04") == [Execute(b"y=2", RAW)]


def test_an_unknown_raw_paste_command_is_refused_with_r_nul():
    repl, link = raw()
    repl.feed(b"\x05B\x01")
    assert link.take() == b"R\x00>"
    assert repl.feed(b"z=3\x04") == [Execute(b"z=3", RAW)]


def test_while_code_runs_ctrl_c_interrupts_and_other_bytes_wait_as_its_stdin():
    repl, link = raw()
    repl.feed(b"input()\x04")
    assert repl.feed(b"ab\x03c") == [Interrupt()]
    assert repl.take_stdin(1) == b"a"
    assert repl.take_stdin() == b"bc"


def test_input_the_code_left_unread_is_handled_by_the_repl_after_it_ends():
    repl, link = raw()
    repl.feed(b"import time; time.sleep(1)\x04")
    link.take()
    assert repl.feed(b"print(3)\x04") == []  # the host typed ahead: it waits
    assert repl.execution_done(None) == [Execute(b"print(3)", RAW)]
    assert link.take() == b"\x04\x04>OK"


def test_the_hub_boots_running_main_and_a_host_break_in_lands_in_the_raw_repl():
    """What mpremote does on connect: \\r Ctrl-C (interrupt main.py), then \\r Ctrl-A."""
    link = Link()
    repl = ReplProtocol(link.write, BANNER)
    assert repl.feed(b"\r\x03") == [Interrupt()]
    assert repl.feed(b"\r\x01") == []
    repl.execution_done("Traceback (most recent call last):\nKeyboardInterrupt: \n")
    assert link.take() == (
        b"Traceback (most recent call last):\r\nKeyboardInterrupt: \r\n"
        + BANNER
        + b">>> \r\n>>> \r\n>>> \r\nraw REPL; CTRL-B to exit\r\n>"
    )
    assert repl.raw_mode


def test_friendly_repl_echoes_and_runs_a_line_on_enter():
    repl, link = booted()
    assert repl.feed(b"1+1") == []
    assert link.take() == b"1+1"
    assert repl.feed(b"\r") == [Execute(b"1+1\n", FRIENDLY)]
    assert link.take() == b"\r\n"
    repl.execution_done(None)
    assert link.take() == b">>> "


def test_friendly_repl_continues_a_compound_statement_until_an_empty_line():
    repl, link = booted()
    assert repl.feed(b"for i in range(2):\r") == []
    assert link.take() == b"for i in range(2):\r\n... "
    assert repl.feed(b"    print(i)\r") == []
    assert repl.feed(b"\r") == [Execute(b"for i in range(2):\n    print(i)\n\n", FRIENDLY)]


def test_friendly_backspace_ctrl_c_and_arrow_keys():
    repl, link = booted()
    repl.feed(b"12\x7f3")
    assert link.take() == b"12\x08 \x083"
    repl.feed(b"\x1b[A\x1b[3~")  # history and delete keys: swallowed
    assert link.take() == b""
    repl.feed(b"\x03")
    assert link.take() == b"\r\n>>> "
    assert repl.feed(b"4\r") == [Execute(b"4\n", FRIENDLY)]


def test_friendly_ctrl_d_soft_reboots_and_ctrl_e_pastes_a_block():
    repl, link = booted()
    assert repl.feed(b"\x04") == [SoftReboot()]
    assert link.take() == b"\r\n"
    repl.execution_done(None)
    assert link.take() == BANNER + b">>> "
    repl.feed(b"\x05")
    assert link.take() == b"\r\npaste mode; Ctrl-C to cancel, Ctrl-D to finish\r\n=== "
    (event,) = repl.feed(b"a = 1\rb = 2\r\x04")
    assert event == Execute(b"a = 1\nb = 2\n", "friendly-paste")


def test_a_hard_reset_drops_typed_ahead_input_and_comes_up_friendly():
    repl, link = raw()
    repl.feed(b"import machine; machine.reset()\x04")
    repl.feed(b"print(5)\x04")
    repl.start_boot()
    assert repl.execution_done(None) == []
    assert not repl.raw_mode


def test_the_window_must_fit_sixteen_bits():
    with pytest.raises(ValueError, match="16-bit"):
        ReplProtocol(Link().write, BANNER, paste_window=70000)
