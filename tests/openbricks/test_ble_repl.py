"""openbricks.ble_repl: the REPL over the Nordic UART Service, seen from the central's side."""

import time

import esp32

from fakes import bluetooth as radio
from fakes import dupterm
from fakes.expect import raises
from openbricks import ble_repl, bluetooth

NUS = ble_repl.NUS_SERVICE_UUID
RX = ble_repl.NUS_RX_UUID
TX = ble_repl.NUS_TX_UUID


def name_hub(name="RobotA"):
    nvs = esp32.NVS("openbricks")
    nvs.set_blob("hub_name", name.encode())
    nvs.commit()


def bridge_up(name="RobotA"):
    name_hub(name)
    radio.radio().active(True)
    ble_repl.start()


def settle():
    """Let scheduled flushes and one pump tick run, as the hub would between two bytecodes."""
    time.sleep_ms(ble_repl.PUMP_MS)


def host_session(mtu=None):
    """A central connects, optionally negotiates the MTU and writes once (it is listening)."""
    conn = radio.connect(0)
    if mtu is not None:
        radio.exchange_mtu(conn, mtu)
    radio.write(conn, RX, b"\x03")  # what a host sends first: interrupt whatever runs
    return conn


def test_registers_the_nordic_uart_service():
    bridge_up()
    services = radio.radio().services
    assert len(services) == 1
    assert str(services[0][0]) == NUS
    assert radio.flags_of(RX) & radio.FLAG_WRITE
    assert radio.flags_of(RX) & radio.FLAG_WRITE_NO_RESPONSE
    assert radio.flags_of(TX) & radio.FLAG_NOTIFY


def test_advertises_the_name_and_the_service():
    bridge_up("Gripper-7")
    assert radio.advertised_name() == "Gripper-7"
    assert radio.advertised_uuid128s() == [NUS]
    assert radio.radio().gap_name == b"Gripper-7"


def test_a_long_name_is_shortened_to_fit_the_advertisement():
    long_name = "TeamRocket-Robot-Number-0042"
    bridge_up(long_name)
    shown = radio.advertised_name()
    assert long_name.startswith(shown) and 0 < len(shown) < len(long_name)
    assert radio.advertised_uuid128s() == [NUS]
    assert radio.radio().gap_name == long_name.encode()  # the GATT device name keeps all of it


def test_host_writes_become_repl_input():
    bridge_up()
    conn = radio.connect(0)
    radio.write(conn, RX, b"print(1+1)\r")
    radio.write(conn, RX, b"\x04")
    assert dupterm.stdin() == b"print(1+1)\r\x04"


def test_a_large_write_split_to_the_mtu_arrives_whole_and_in_order():
    bridge_up()
    conn = radio.connect(0)
    radio.exchange_mtu(conn, 185)
    program = bytes(range(256)) * 4
    radio.write_stream(conn, RX, program)
    assert dupterm.stdin() == program


def test_ctrl_c_interrupts_a_running_program():
    bridge_up()
    conn = radio.connect(0)
    dupterm.executing(True)
    radio.write(conn, RX, b"\x03")
    assert dupterm.interrupts() == 1
    assert dupterm.stdin() == b""


def test_ctrl_c_is_plain_input_while_the_repl_waits():
    # The raw REPL reads Ctrl-C as "clear the line" when nothing is running.
    bridge_up()
    conn = radio.connect(0)
    radio.write(conn, RX, b"\x03")
    assert dupterm.interrupts() == 0
    assert dupterm.stdin() == b"\x03"


def test_the_repl_stream_stays_attached_when_drained():
    # An empty read must not look like end-of-file, which would detach the REPL from BLE for good.
    bridge_up()
    conn = radio.connect(0)
    radio.write(conn, RX, b"a")
    dupterm.dupterm_notify(None)
    assert dupterm.attached() is not None
    radio.write(conn, RX, b"b")
    assert dupterm.stdin() == b"ab"


def test_output_is_chunked_to_the_negotiated_mtu():
    bridge_up()
    conn = host_session(mtu=100)
    text = b"".join(b"line %03d of the program output\r\n" % i for i in range(40))
    dupterm.repl_print(text)
    settle()
    sizes = [len(p) for p in radio.notifications(conn)]
    assert radio.received(conn) == text
    assert max(sizes) == 97
    assert all(size == 97 for size in sizes[:-1])


def test_before_the_mtu_exchange_chunks_fit_the_default_mtu():
    bridge_up()
    conn = host_session()
    dupterm.repl_print(b"x" * 50)
    settle()
    assert [len(p) for p in radio.notifications(conn)] == [20, 20, 10]


def test_output_waits_until_the_central_listens():
    bridge_up()
    dupterm.repl_print("boot banner\r\n")
    conn = radio.connect(0)
    dupterm.repl_print("hello\r\n")
    settle()
    assert radio.received(conn) == b""  # not subscribed yet as far as the hub knows
    radio.write(conn, RX, b"\x01")
    settle()
    assert radio.received(conn) == b"boot banner\r\nhello\r\n"


def test_a_central_that_only_listens_gets_output_after_the_grace_period():
    bridge_up()
    conn = radio.connect(0)
    dupterm.repl_print("tick\r\n")
    time.sleep_ms(ble_repl.CONNECT_GRACE_MS - 100)
    assert radio.received(conn) == b""
    time.sleep_ms(200)
    assert radio.received(conn) == b"tick\r\n"


def test_output_made_during_a_dropout_reaches_the_reconnected_host():
    bridge_up()
    conn = host_session()
    dupterm.repl_print("before\r\n")
    settle()
    radio.disconnect(conn)
    assert radio.advertised_name() == "RobotA"  # findable again at once
    dupterm.repl_print("during\r\n")
    conn = host_session()
    settle()
    assert radio.received(conn) == b"during\r\n"


def test_a_long_dropout_keeps_the_newest_output():
    bridge_up()
    lines = [b"%05d\n" % i for i in range(2000)]
    for line in lines:
        dupterm.repl_print(line)
    conn = host_session(mtu=247)
    settle()
    got = radio.received(conn)
    assert len(got) == ble_repl.TX_BUFFER_BYTES
    assert b"".join(lines).endswith(got)


def test_full_controller_buffers_delay_output_but_lose_none():
    bridge_up()
    conn = host_session()
    radio.limit_notifications(2)
    text = bytes(range(48, 48 + 64)) * 3
    dupterm.repl_print(text)
    time.sleep_ms(0)  # the flush repl_print scheduled runs at the next pending check, not inside it
    assert len(radio.notifications(conn)) == 2
    radio.limit_notifications(None)  # the controller drained its queue
    settle()
    assert radio.received(conn) == text


def test_the_pump_finishes_output_when_no_further_write_comes():
    bridge_up()
    conn = host_session()
    radio.limit_notifications(0)
    dupterm.repl_print(">OK\x04\x04>")  # the raw-REPL terminator: nothing is printed after it
    settle()
    assert radio.received(conn) == b""
    radio.limit_notifications(None)
    settle()
    assert radio.received(conn) == b">OK\x04\x04>"


def test_a_second_central_is_turned_away():
    bridge_up()
    first = host_session()
    radio.connect(1, racing=True)
    assert list(radio.radio().connections) == [first]
    dupterm.repl_print("only for the first")
    settle()
    assert radio.received(first) == b"only for the first"


def test_stop_detaches_the_repl_drops_the_link_and_goes_quiet():
    bridge_up()
    host_session()
    ble_repl.stop()
    assert not ble_repl.is_running()
    assert dupterm.attached() is None
    assert radio.radio().connections == {}
    assert radio.radio().advertising is None
    ble_repl.stop()  # idempotent


def test_start_is_idempotent_and_restartable():
    bridge_up()
    ble_repl.start()
    assert len(radio.radio().services) == 1
    ble_repl.stop()
    ble_repl.start()
    conn = host_session()
    dupterm.repl_print("again")
    settle()
    assert radio.received(conn) == b"again"


def test_stop_completes_even_if_the_radio_went_down_first():
    bridge_up()
    host_session()
    radio.radio().active(False)
    ble_repl.stop()
    assert not ble_repl.is_running()
    assert dupterm.attached() is None


def test_start_needs_the_radio_on():
    name_hub()
    with raises(OSError, "set_enabled(True)"):
        ble_repl.start()
    assert not ble_repl.is_running()


def test_start_needs_a_hub_name():
    radio.radio().active(True)
    with raises(bluetooth.HubNameNotSetError):
        ble_repl.start()
    assert radio.radio().advertising is None


def test_link_events_are_logged_in_a_bounded_ring():
    bridge_up()
    for _ in range(40):
        conn = host_session(mtu=247)
        radio.disconnect(conn)
    entries = ble_repl.log_entries()
    assert len(entries) == 32
    texts = [text for _stamp, text in entries]
    assert texts[-1].startswith("disconnected 0")
    assert "mtu 247" in texts
    ble_repl.clear_log()
    assert ble_repl.log_entries() == []
