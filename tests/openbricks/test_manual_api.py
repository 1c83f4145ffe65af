"""The names the manual's API chapter (7) documents, called the way the manual writes them.

Each call spells the manual's signature (its keyword names, its positional order), so a renamed or
missing parameter fails here under CPython and the MicroPython interpreter alike.
"""

import time

import machine

import openbricks
from fakes import tmpdir
from fakes.i2c_chips import TCS34725Chip
from openbricks import bluetooth, host_calls, launcher, pins, tools
from openbricks.drivers.tcs34725 import TCS34725


def test_hub_name_is_a_module_attribute_that_follows_the_flashed_name():
    assert openbricks.HUB_NAME is None or isinstance(openbricks.HUB_NAME, str)
    host_calls.set_hub_name("RobotA")  # what `openbricks flash --name RobotA` leaves in NVS
    assert openbricks.HUB_NAME == "RobotA" == bluetooth.hub_name()


def test_tcs34725_reflection_reads_the_lit_surface_0_to_100():
    chip = TCS34725Chip()
    machine.board.attach_i2c(0, 0x29, chip)
    sensor = TCS34725(machine.I2C(0))
    chip.light = (0, 0, 0, 0)
    assert sensor.reflection() == 0
    chip.light = (400, 100, 100, 100)
    assert 0 < sensor.reflection() <= 100 and sensor.reflection() == sensor.ambient()


def test_launcher_timing_constants_are_class_attributes_with_the_manuals_values():
    expected = {
        "START_LOCKOUT_MS": 500,
        "STOP_RETRY_MS": 300,
        "STARVE_NOTE_MS": 5000,
        "DEBOUNCE_TICKS": 2,
        "RUN_START_GRACE_MS": 400,
        "START_PRESS_OPEN_MS": 600,
        "RELEASE_CHATTER_MS": 500,
    }
    for name, value in expected.items():
        assert getattr(launcher.Launcher, name) == value, name


def test_launcher_takes_its_button_as_button():
    pins.reset_claims()
    with tmpdir.scratch() as directory:
        hub = launcher.Launcher(button=39, program_path=directory + "/program.py", poll_ms=50)
        assert pins.owner_of(39) == ("program button", "launcher")
        pin = machine.Pin(40, machine.Pin.IN)
        assert launcher.Launcher(button=pin, program_path=hub.program_path).button_pin is None
    pins.reset_claims()


def test_pins_claim_takes_pin_role_and_hint_and_the_runtime_owns_it():
    pins.reset_claims()
    pins.claim(39, "program button", "pass button_pin= to launcher.run()")
    assert pins.owner_of(39) == ("program button", pins.RUNTIME_OWNER)
    try:
        pins.check(39, "HC-SR04 echo", output=False)
        raise AssertionError("a driver on the runtime's pin must be refused")
    except pins.ReservedPinError as exc:
        assert "in use as the program button" in str(exc)
        assert "pass button_pin= to launcher.run()" in str(exc)
    pins.claim(39, "program button")  # the runtime re-wiring its own pin
    pins.reset_claims()


def test_tools_wait_takes_milliseconds():
    start = time.ticks_ms()
    tools.wait(milliseconds=30)
    assert time.ticks_diff(time.ticks_ms(), start) >= 30
