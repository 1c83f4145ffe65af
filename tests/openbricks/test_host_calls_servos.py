"""The host's servo calls on the hub: the bus scanned, and a servo re-IDed with the safety rules."""

import machine

from fakes.scs_servo import FakeServo, ScsBus, scs
from openbricks import host_calls

NEEDS_NATIVE = True  # the servos are the simulator's, on the native SCS codec


def _servo_bus(*ids):
    bus = ScsBus()
    for servo_id in ids:
        bus.add(FakeServo(servo_id))
    machine.board.attach_uart(1, bus)
    return bus


def test_servo_scan_lists_the_ids_that_answer_and_changes_nothing():
    bus = _servo_bus(1, 2, 17)
    result = host_calls.servo_scan()
    assert result["ids"] == [1, 2, 17]
    assert result["bus"] == "UART1 tx=14 rx=41"
    assert all(servo.writes == [] for servo in bus.servos.values())


def test_re_id_with_several_servos_requires_old_id_and_never_guesses():
    bus = _servo_bus(1, 2)
    result = host_calls.servo_set_id(5)
    assert not result["ok"] and "2 servos answer (ids 1, 2): pass old_id=" in result["error"]
    assert sorted(bus.servos) == [1, 2]


def test_re_id_rewrites_the_id_and_verifies_it_by_read_back():
    bus = _servo_bus(1, 2)
    servo = bus.servo(2)
    result = host_calls.servo_set_id(5, old_id=2)
    assert result == {"ok": True, "old_id": 2, "new_id": 5, "ids": [1, 5], "changed": True}
    assert servo.servo_id == 5
    # EEPROM unlocked, id written, locked again: the new id survives a power cycle.
    assert servo.writes == [(scs.REG_LOCK, b"\x00"), (scs.REG_ID, b"\x05"), (scs.REG_LOCK, b"\x01")]


def test_a_single_servo_is_found_without_old_id_and_taken_ids_are_refused():
    _servo_bus(1)
    assert host_calls.servo_set_id(3)["ids"] == [3]
    _servo_bus(3, 4)
    taken = host_calls.servo_set_id(4, old_id=3)
    assert not taken["ok"] and "id 4 is already taken" in taken["error"]
    missing = host_calls.servo_set_id(9, old_id=8)
    assert not missing["ok"] and "no servo answers at old_id=8; the bus has ids 3, 4" in missing["error"]
    assert "bus ids are 0..253" in host_calls.servo_set_id(254, old_id=3)["error"]


def test_re_id_on_a_silent_bus_points_at_power_and_wiring():
    _servo_bus()
    result = host_calls.servo_set_id(3)
    assert not result["ok"] and "no servo answers on UART1 tx=14 rx=41" in result["error"]
