"""The reserved-GPIO guard refuses the wiring mistakes the manual lists, naming pin, role and owner."""

from fakes.expect import raises
from openbricks import pins


def _setup(chip=None, psram=False):
    pins.reset_claims()
    pins.set_chip(chip, psram)


def test_nonexistent_s3_pin_is_refused_with_pin_role_and_usable_range():
    _setup("esp32s3")
    with raises(pins.ReservedPinError, "GPIO 23 can't be used as L298N IN1 for L298N") as err:
        pins.claim(23, "L298N IN1", owner="L298N")
    assert err.value.pin == 23
    assert err.value.role == "L298N IN1"
    assert "doesn't exist on the ESP32-S3" in err.value.reason
    assert "0-21 and 26-48" in str(err.value)
    assert pins.owner_of(23) is None


def test_s3_flash_and_usb_pins_are_refused_but_strapping_pins_are_allowed():
    _setup("esp32s3")
    with raises(pins.ReservedPinError, "SPI flash"):
        pins.claim(30, "SSD1306 SDA", owner="SSD1306")
    with raises(pins.ReservedPinError, "native-USB"):
        pins.claim(20, "HC-SR04 trig", owner="HCSR04")
    for strapping in (0, 3, 45, 46):
        pins.claim(strapping, "QTR channel", owner="QTR")
    # 33-37 are ordinary GPIOs unless the module has octal PSRAM.
    pins.claim(35, "TB6612 PWMA", owner="TB6612")


def test_octal_psram_module_also_reserves_33_to_37():
    _setup("esp32s3", psram=True)
    with raises(pins.ReservedPinError, "octal PSRAM"):
        pins.claim(35, "TB6612 PWMA", owner="TB6612")


def test_classic_esp32_input_only_pins_refuse_outputs_but_accept_inputs():
    _setup("esp32")
    with raises(pins.ReservedPinError, "input-only"):
        pins.claim(36, "L298N ENA", owner="L298N")
    pins.claim(36, "HC-SR04 echo", owner="HCSR04", output=False)
    with raises(pins.ReservedPinError, "SPI flash"):
        pins.claim(7, "encoder A", owner="JGB37")
    with raises(pins.ReservedPinError, "doesn't exist on the ESP32"):
        pins.claim(24, "encoder B", owner="JGB37", output=False)


def test_pin_held_by_the_runtime_names_the_owner_and_how_to_move_it():
    _setup("esp32s3")
    pins.claim(39, "program button", owner="launcher", hint="pass button_pin= to Launcher() to move it")
    with raises(pins.ReservedPinError, "in use as the program button (owner: launcher)") as err:
        pins.claim(39, "HC-SR04 echo", owner="HCSR04")
    assert err.value.owner == "launcher"
    assert err.value.requester == "HCSR04"
    assert "button_pin=" in str(err.value)


def test_driver_objects_can_own_pins_and_two_instances_conflict():
    _setup()

    class HCSR04:
        pass

    first, second = HCSR04(), HCSR04()
    pins.claim(5, "HC-SR04 trig", owner=first)
    pins.claim(5, "HC-SR04 trig", owner=first)  # re-initialising the same driver is fine
    with raises(pins.ReservedPinError, "owner: HCSR04"):
        pins.claim(5, "HC-SR04 trig", owner=second)
    pins.release(5, first)
    pins.claim(5, "HC-SR04 trig", owner=second)


def test_release_refuses_to_free_another_owners_pin_and_ignores_unknown_pins():
    _setup()
    pins.claim(38, "Bluetooth button", owner="hub")
    with raises(ValueError, "only its owner can release it"):
        pins.release(38, "L298N")
    pins.release(12, "L298N")
    pins.release(38)
    assert pins.owner_of(38) is None


def test_off_chip_only_ownership_is_checked():
    _setup()
    assert pins.chip() is None
    pins.claim(24, "fake pin", owner="sim")  # no wiring rules off-chip
    with raises(pins.ReservedPinError, "in use as the fake pin"):
        pins.check(24, "other", owner="someone")


def test_machine_strings_of_real_firmware_are_recognised():
    parse = pins._parse_machine
    assert parse("ESP32S3 module with ESP32S3") == ("esp32s3", False)
    assert parse("ESP32S3 module (spiram octal) with ESP32S3") == ("esp32s3", True)
    assert parse("Generic ESP32 module with ESP32") == ("esp32", False)
    assert parse("Generic ESP32 module with SPIRAM with ESP32") == ("esp32", True)
    assert parse("ESP32C3 module with ESP32C3") == (None, False)
    assert parse("x86_64") == (None, False)


def test_unknown_chip_override_is_rejected():
    _setup()
    with raises(ValueError, "use 'esp32', 'esp32s3' or None"):
        pins.set_chip("rp2040")


def test_claims_made_after_a_snapshot_are_released_so_a_program_can_run_twice():
    _setup()
    pins.claim(39, "program button", owner="launcher")
    before = pins.snapshot()
    pins.claim(5, "HC-SR04 trig", owner=object())
    pins.release_since(before)
    assert pins.owner_of(5) is None
    assert pins.owner_of(39) == ("program button", "launcher")
