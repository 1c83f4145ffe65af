"""openbricks.bluetooth: BLE on/off persisted in NVS, the hub-name rule, state listeners."""

import time

import esp32

from fakes import bluetooth as radio
from fakes import dupterm
from fakes.expect import raises
from openbricks import ble_repl, bluetooth


def name_hub(name):
    nvs = esp32.NVS("openbricks")
    nvs.set_blob("hub_name", name.encode())
    nvs.commit()


def reboot():
    """Power-cycle: RAM state and the radio are gone, NVS survives."""
    radio.reset()
    dupterm.reset()
    bluetooth.reset_state()
    ble_repl.reset_state()


def test_first_boot_comes_up_advertising_the_flashed_name():
    name_hub("RobotA")
    assert bluetooth.is_enabled()
    assert bluetooth.apply_persisted_state() is True
    assert radio.radio().active()
    assert radio.advertised_name() == "RobotA"
    assert ble_repl.NUS_SERVICE_UUID in radio.advertised_uuid128s()
    assert bluetooth.is_active()


def test_hub_name_is_read_from_nvs():
    assert bluetooth.hub_name() is None
    name_hub("Gripper-7")
    assert bluetooth.hub_name() == "Gripper-7"


def test_off_survives_a_reboot():
    name_hub("RobotA")
    bluetooth.apply_persisted_state()
    bluetooth.set_enabled(False)
    assert not radio.radio().active()
    reboot()
    assert bluetooth.is_enabled() is False
    assert bluetooth.apply_persisted_state() is False
    assert not radio.radio().active()
    assert radio.radio().advertising is None


def test_on_survives_a_reboot():
    name_hub("RobotA")
    bluetooth.set_enabled(False)
    bluetooth.set_enabled(True)
    reboot()
    assert bluetooth.apply_persisted_state() is True
    assert radio.advertised_name() == "RobotA"


def test_turning_on_a_nameless_hub_is_refused_and_changes_nothing():
    bluetooth.set_enabled(False)
    with raises(bluetooth.HubNameNotSetError, "openbricks flash --name NAME"):
        bluetooth.set_enabled(True)
    assert bluetooth.is_enabled() is False
    assert not radio.radio().active()


def test_a_nameless_hub_can_always_be_silenced():
    bluetooth.set_enabled(False)
    assert bluetooth.is_enabled() is False
    assert not bluetooth.is_active()


def test_boot_with_no_name_stays_off_instead_of_raising():
    assert bluetooth.is_enabled()  # the stored state says "on"
    assert bluetooth.apply_persisted_state() is False
    assert not radio.radio().active()
    assert not ble_repl.is_running()


def test_toggle_flips_and_reports_the_new_state():
    name_hub("RobotA")
    bluetooth.apply_persisted_state()
    assert bluetooth.toggle() is False
    assert not radio.radio().active()
    assert bluetooth.toggle() is True
    assert radio.radio().active()
    assert radio.advertised_name() == "RobotA"


def test_turning_off_drops_the_link_and_detaches_the_repl_before_the_radio():
    name_hub("RobotA")
    bluetooth.apply_persisted_state()
    radio.connect(0)
    assert dupterm.attached() is not None
    bluetooth.set_enabled(False)
    assert dupterm.attached() is None
    assert radio.radio().connections == {}
    assert not radio.radio().active()


def test_reapplying_the_state_keeps_a_live_link():
    # A program constructing a hub re-applies the state while the host is connected over BLE.
    name_hub("RobotA")
    bluetooth.apply_persisted_state()
    radio.connect(0)
    radio.write(0, ble_repl.NUS_RX_UUID, b"\x01")
    bluetooth.apply_persisted_state()
    assert 0 in radio.radio().connections
    assert radio.radio().activations == 1
    dupterm.repl_print("still here")
    time.sleep_ms(ble_repl.PUMP_MS)
    assert radio.received(0).endswith(b"still here")


def test_listeners_hear_every_change_once_each():
    name_hub("RobotA")
    heard = []
    bluetooth.add_state_listener(heard.append)
    bluetooth.add_state_listener(heard.append)
    bluetooth.apply_persisted_state()
    bluetooth.toggle()
    bluetooth.set_enabled(True)
    assert heard == [True, False, True]
    bluetooth.remove_state_listener(heard.append)
    bluetooth.remove_state_listener(heard.append)  # unknown: no-op
    bluetooth.toggle()
    assert heard == [True, False, True]


def test_a_failing_listener_does_not_starve_the_others():
    name_hub("RobotA")
    heard = []

    def broken(active):
        raise ValueError("listener bug")

    bluetooth.add_state_listener(broken)
    bluetooth.add_state_listener(heard.append)
    with raises(ValueError, "listener bug"):
        bluetooth.set_enabled(False)
    assert heard == [False]
    assert bluetooth.is_enabled() is False
