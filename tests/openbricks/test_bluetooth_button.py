"""openbricks.bluetooth_button: the BLE toggle press and the status LED's colours and rhythms.

The button is a real PushButton on GPIO 38 driven through the fake board; the LED is read back as the
bytes a WS2812 on GPIO 48 receives (brightness 1.0, so colours come through unscaled).
"""

import time

import esp32
from machine import board

from fakes import bluetooth as radio
from openbricks import bluetooth, bluetooth_button
from openbricks.bluetooth_button import BluetoothToggleButton
from openbricks.hub import NeoPixelLED, PushButton, SimpleLED

BUTTON = 38
LED = 48
BLUE = bluetooth_button.DEFAULT_COLOR_ON
YELLOW = bluetooth_button.DEFAULT_COLOR_OFF
RED = bluetooth_button.COLOR_START_PRESS
GREEN = bluetooth_button.COLOR_STOP_PRESS
DARK = (0, 0, 0)


def name_hub():
    nvs = esp32.NVS("openbricks")
    nvs.set_blob("hub_name", b"RobotA")
    nvs.commit()


def led_colour():
    """What the WS2812 shows: the last GRB frame sent on its pin, as (r, g, b)."""
    frames = [data for pin, _timing, data in board.bitstreams if pin == LED]
    g, r, b = frames[-1][0], frames[-1][1], frames[-1][2]
    return (r, g, b)


def watcher(running=None, led=True):
    flag = [False] if running is None else running
    toggle = BluetoothToggleButton(
        PushButton(BUTTON),
        led=NeoPixelLED(LED, brightness=1.0) if led else None,
        program_running=lambda: flag[0],
    )
    return toggle.start(), flag


def press(hold_ms=200):
    board.set_input(BUTTON, 0)
    time.sleep_ms(hold_ms)
    board.set_input(BUTTON, 1)
    time.sleep_ms(200)


def test_the_led_shows_blue_when_ble_is_on():
    name_hub()
    bluetooth.apply_persisted_state()
    watcher()
    assert led_colour() == BLUE


def test_the_led_shows_yellow_when_ble_is_off():
    bluetooth.set_enabled(False)
    watcher()
    assert led_colour() == YELLOW


def test_each_press_release_toggles_ble_once():
    name_hub()
    bluetooth.apply_persisted_state()
    watcher()
    press()
    assert bluetooth.is_enabled() is False
    assert not radio.radio().active()
    assert led_colour() == YELLOW
    press()
    assert bluetooth.is_enabled() is True
    assert radio.advertised_name() == "RobotA"
    assert led_colour() == BLUE


def test_holding_the_button_toggles_only_on_release():
    name_hub()
    bluetooth.apply_persisted_state()
    watcher()
    board.set_input(BUTTON, 0)
    time.sleep_ms(3000)
    assert bluetooth.is_enabled() is True
    board.set_input(BUTTON, 1)
    time.sleep_ms(200)
    assert bluetooth.is_enabled() is False


def test_a_glitch_shorter_than_the_debounce_is_ignored():
    name_hub()
    bluetooth.apply_persisted_state()
    watcher()
    press(hold_ms=bluetooth_button.DEFAULT_POLL_MS)  # seen low on one poll only
    assert bluetooth.is_enabled() is True


def test_the_led_follows_ble_changes_made_without_the_button():
    name_hub()
    bluetooth.apply_persisted_state()
    watcher()
    bluetooth.set_enabled(False)
    assert led_colour() == YELLOW
    bluetooth.set_enabled(True)
    assert led_colour() == BLUE


def sample(duration_ms, step_ms=10):
    """Sample the LED every step_ms: list of (t_ms, colour)."""
    samples = []
    t = 0
    while t < duration_ms:
        samples.append((t, led_colour()))
        time.sleep_ms(step_ms)
        t += step_ms
    return samples


def test_a_running_program_flashes_the_state_colour_at_2_hz():
    name_hub()
    bluetooth.apply_persisted_state()
    _toggle, running = watcher()
    running[0] = True
    time.sleep_ms(bluetooth_button.DEFAULT_POLL_MS)
    samples = sample(2000)
    changes = [samples[i][0] for i in range(1, len(samples)) if samples[i][1] != samples[i - 1][1]]
    gaps = [changes[i] - changes[i - 1] for i in range(1, len(changes))]
    assert len(changes) >= 7  # four on/off cycles in two seconds
    assert all(200 <= gap <= 300 for gap in gaps), gaps
    assert {colour for _t, colour in samples} == {BLUE, DARK}
    running[0] = False
    time.sleep_ms(100)
    assert led_colour() == BLUE  # solid again when the program stops


def test_the_flash_uses_yellow_when_ble_is_off():
    bluetooth.set_enabled(False)
    _toggle, running = watcher()
    running[0] = True
    seen = set()
    for _ in range(20):
        time.sleep_ms(50)
        seen.add(led_colour())
    assert seen == {YELLOW, DARK}


def test_a_start_press_flashes_red_then_the_led_carries_on():
    name_hub()
    bluetooth.apply_persisted_state()
    watcher()
    bluetooth_button.notify_press()
    time.sleep_ms(bluetooth_button.DEFAULT_POLL_MS)
    assert led_colour() == RED
    time.sleep_ms(bluetooth_button.ACK_MS + bluetooth_button.DEFAULT_POLL_MS)
    assert led_colour() == BLUE


def test_a_stop_press_flashes_green_even_during_the_run_flash():
    name_hub()
    bluetooth.apply_persisted_state()
    _toggle, running = watcher()
    running[0] = True
    time.sleep_ms(400)
    bluetooth_button.notify_press(stop=True)
    time.sleep_ms(bluetooth_button.DEFAULT_POLL_MS)
    colours = set()
    for _ in range(4):
        colours.add(led_colour())
        time.sleep_ms(50)
    assert colours == {GREEN}


def test_a_single_colour_led_blinks_during_a_run_and_is_dark_at_idle():
    name_hub()
    bluetooth.apply_persisted_state()
    flag = [False]
    BluetoothToggleButton(PushButton(BUTTON), led=SimpleLED(2), program_running=lambda: flag[0]).start()
    assert board.pins[2].value() == 0
    flag[0] = True
    levels = set()
    for _ in range(20):
        time.sleep_ms(50)
        levels.add(board.pins[2].value())
    assert levels == {0, 1}
    flag[0] = False
    time.sleep_ms(100)
    assert board.pins[2].value() == 0
    bluetooth_button.notify_press()
    time.sleep_ms(bluetooth_button.DEFAULT_POLL_MS)
    assert board.pins[2].value() == 1  # a press still gets a visible acknowledgment


def test_a_press_on_a_nameless_hub_keeps_ble_off_and_the_watcher_alive():
    bluetooth.set_enabled(False)
    watcher()
    press()
    assert not radio.radio().active()
    assert led_colour() == YELLOW
    name_hub()
    press()  # still watching: naming the hub makes the next press work
    assert radio.radio().active()
    assert led_colour() == BLUE


def test_stop_ends_the_watching():
    name_hub()
    bluetooth.apply_persisted_state()
    toggle, _running = watcher()
    toggle.stop()
    toggle.stop()
    assert not toggle.is_running()
    press()
    assert bluetooth.is_enabled() is True
    frames = len(board.bitstreams)
    bluetooth.set_enabled(False)
    assert len(board.bitstreams) == frames  # no longer following the state


def test_starting_twice_keeps_one_watcher():
    name_hub()
    bluetooth.apply_persisted_state()
    toggle, _running = watcher()
    toggle.start()
    press()
    assert bluetooth.is_enabled() is False


def test_without_an_led_the_button_still_toggles():
    name_hub()
    bluetooth.apply_persisted_state()
    watcher(led=False)
    press()
    assert bluetooth.is_enabled() is False
