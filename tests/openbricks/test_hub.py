"""openbricks.hub: the devkit hubs, their LEDs and buttons, seen on the fake board's pins and wire."""

import time

import esp32
from machine import Pin, board

from fakes import bluetooth as radio
from fakes.expect import raises
from openbricks import bluetooth, hub, pins
from openbricks.hub import ESP32DevkitHub, ESP32S3DevkitHub, NeoPixelLED, PushButton, SimpleLED


def name_hub():
    nvs = esp32.NVS("openbricks")
    nvs.set_blob("hub_name", b"RobotA")
    nvs.commit()


def pixel(pin=48):
    """The last (r, g, b) a WS2812 on `pin` received (its wire order is G, R, B)."""
    frames = [data for p, _timing, data in board.bitstreams if p == pin]
    assert frames, "nothing was ever sent to a WS2812 on GPIO %d" % pin
    g, r, b = frames[-1][0], frames[-1][1], frames[-1][2]
    return (r, g, b)


def press(pin):
    board.set_input(pin, 0)
    time.sleep_ms(200)
    board.set_input(pin, 1)
    time.sleep_ms(200)


def test_s3_hub_restores_ble_and_paints_the_led_blue():
    name_hub()
    h = ESP32S3DevkitHub()
    assert radio.advertised_name() == "RobotA"
    assert pixel(48) == (0, 0, int(255 * 0.2))  # blue at the default brightness
    assert h.bluetooth_toggle.is_running()


def test_s3_hub_paints_yellow_when_ble_was_left_off():
    bluetooth.set_enabled(False)
    ESP32S3DevkitHub()
    r, g, b = pixel(48)
    assert r > g > 0 and b == 0
    assert not radio.radio().active()


def test_the_s3_ble_button_toggles_ble():
    name_hub()
    ESP32S3DevkitHub()
    press(38)
    assert bluetooth.is_enabled() is False
    assert not radio.radio().active()


def test_led_rgb_is_scaled_by_brightness_on_the_wire():
    h = ESP32S3DevkitHub(bluetooth=False)
    h.led.rgb(0, 80, 0)
    assert pixel(48) == (0, 16, 0)
    bright = ESP32S3DevkitHub(bluetooth=False, brightness=1.0)
    bright.led.rgb(10, 20, 30)
    assert pixel(48) == (10, 20, 30)


def test_led_on_restores_the_last_colour():
    h = ESP32S3DevkitHub(bluetooth=False, brightness=1.0)
    h.led.rgb(1, 2, 3)
    h.led.off()
    assert pixel(48) == (0, 0, 0)
    h.led.on()
    assert pixel(48) == (1, 2, 3)


def test_led_rejects_out_of_range_channels():
    h = ESP32S3DevkitHub(bluetooth=False)
    with raises(ValueError, "0..255, got r=256"):
        h.led.rgb(256, 0, 0)
    with raises(ValueError, "got b=-1"):
        h.led.rgb(0, 0, -1)


def test_brightness_must_be_a_fraction():
    with raises(ValueError, "brightness must be 0.0-1.0"):
        ESP32S3DevkitHub(brightness=20)
    with raises(ValueError, "brightness must be 0.0-1.0"):
        NeoPixelLED(21, brightness=-0.1)


def test_without_bluetooth_the_button_is_left_to_the_user():
    h = ESP32S3DevkitHub(bluetooth=False)
    assert h.bluetooth_toggle is None
    assert not radio.radio().active()
    assert not h.bluetooth_button.pressed()
    board.set_input(38, 0)
    assert h.bluetooth_button.pressed()
    time.sleep_ms(500)
    assert bluetooth.is_enabled() is True  # nothing toggled


def test_the_button_pin_has_an_internal_pull_up():
    ESP32S3DevkitHub(bluetooth=False)
    assert board.pins[38]._mode == Pin.IN
    assert board.pins[38]._pull == Pin.PULL_UP


def test_a_driver_on_the_ble_button_pin_is_told_who_owns_it():
    ESP32S3DevkitHub(bluetooth=False)
    with raises(pins.ReservedPinError, "in use as the Bluetooth button") as err:
        pins.claim(38, "QTR channel 1", owner="QTRLineSensor")
    assert "ESP32S3DevkitHub" in str(err.value)
    assert "bluetooth_button_pin=" in str(err.value)


def test_a_driver_on_the_led_pin_is_told_who_owns_it():
    ESP32S3DevkitHub(bluetooth=False)
    with raises(pins.ReservedPinError, "in use as the status LED") as err:
        pins.claim(48, "WS2812 data", owner="WS2812")
    assert "led_pin=" in str(err.value)


def test_moved_pins_free_the_defaults():
    h = ESP32S3DevkitHub(led_pin=21, bluetooth_button_pin=5, bluetooth=False)
    pins.claim(38, "encoder A", owner="JGB37Motor")
    pins.claim(48, "encoder B", owner="JGB37Motor")
    h.led.rgb(255, 255, 255)
    assert pixel(21) == (51, 51, 51)
    with raises(pins.ReservedPinError, "Bluetooth button"):
        pins.claim(5, "trigger", owner="HCSR04")


def test_led_pin_none_leaves_the_led_alone():
    h = ESP32S3DevkitHub(led_pin=None, bluetooth=False)
    assert h.led is None
    pins.claim(48, "WS2812 data", owner="WS2812")
    assert [p for p, _t, _d in board.bitstreams] == []


def test_a_busy_button_pin_fails_the_hub_and_frees_the_led_pin():
    pins.claim(38, "echo", owner="HCSR04")
    with raises(pins.ReservedPinError, "in use as the echo"):
        ESP32S3DevkitHub(bluetooth=False)
    pins.claim(48, "WS2812 data", owner="WS2812")  # not left claimed by the failed hub


def test_led_and_button_on_one_pin_is_refused():
    with raises(ValueError, "both GPIO 38"):
        ESP32S3DevkitHub(led_pin=38)


def test_a_second_hub_replaces_the_first_so_one_press_is_one_toggle():
    # The frozen main.py wires a hub at boot; a program constructing its own must not double up.
    name_hub()
    first = ESP32S3DevkitHub()
    second = ESP32S3DevkitHub()
    assert first.bluetooth_toggle is None  # retired: its watcher is stopped
    assert hub.current() is second
    press(38)
    assert bluetooth.is_enabled() is False


def test_close_releases_the_hub():
    name_hub()
    h = ESP32S3DevkitHub()
    h.close()
    assert hub.current() is None
    assert pixel(48) == (0, 0, 0)
    pins.claim(38, "echo", owner="HCSR04")
    press(38)
    assert bluetooth.is_enabled() is True


def test_classic_hub_drives_the_blue_led_on_gpio_2():
    bluetooth.set_enabled(False)
    h = ESP32DevkitHub()
    assert board.pins[2].value() == 0  # dark at idle
    h.led.on()
    assert board.pins[2].value() == 1
    h.led.off()
    assert board.pins[2].value() == 0
    with raises(NotImplementedError, "GPIO 2 is single-colour"):
        h.led.rgb(0, 0, 255)


def test_classic_hub_ble_button_is_gpio_5():
    name_hub()
    ESP32DevkitHub()
    press(5)
    assert bluetooth.is_enabled() is False


def test_an_active_low_led_is_inverted_on_the_pin():
    led = SimpleLED(13, active_high=False)
    assert board.pins[13].value() == 1  # dark
    led.on()
    assert board.pins[13].value() == 0


def test_an_active_high_button_uses_a_pull_down():
    button = PushButton(14, active_low=False)
    assert board.pins[14]._pull == Pin.PULL_DOWN
    assert not button.pressed()
    board.set_input(14, 1)
    assert button.pressed()


def test_standalone_peripherals_claim_their_pins():
    SimpleLED(13)
    with raises(pins.ReservedPinError, "status LED"):
        PushButton(13)


def test_for_this_board_picks_the_hub_of_the_chip():
    pins.set_chip(pins.ESP32S3)
    assert isinstance(hub.for_this_board(bluetooth=False), ESP32S3DevkitHub)
    pins.set_chip(pins.ESP32)
    assert isinstance(hub.for_this_board(bluetooth=False), ESP32DevkitHub)


def test_for_this_board_off_chip_says_what_to_do():
    with raises(OSError, "construct ESP32DevkitHub() or ESP32S3DevkitHub() explicitly"):
        hub.for_this_board()
