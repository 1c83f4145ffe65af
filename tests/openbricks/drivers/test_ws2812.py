"""WS2812: what goes down the data wire (GRB bytes, brightness-scaled) and when."""

from machine import board

from fakes.expect import raises
from openbricks import pins
from openbricks.drivers.ws2812 import WS2812


def _last_frame():
    pin, _timing, data = board.bitstreams[-1]
    return pin, [tuple(data[i : i + 3]) for i in range(0, len(data), 3)]


def test_fill_pushes_every_led_in_green_red_blue_order_scaled_by_brightness():
    strip = WS2812(pin=21, n=4, brightness=0.5)
    strip.fill((200, 100, 50))
    pin, frame = _last_frame()
    assert pin == 21
    assert frame == [(50, 100, 25)] * 4


def test_assignments_are_buffered_until_show():
    strip = WS2812(pin=21, n=3, brightness=1.0)
    strip[0] = (255, 0, 0)
    strip[2] = (0, 0, 255)
    assert board.bitstreams == []
    strip.show()
    assert len(board.bitstreams) == 1
    assert _last_frame()[1] == [(0, 255, 0), (0, 0, 0), (0, 0, 255)]


def test_colours_read_back_unscaled_and_rescale_when_brightness_changes():
    strip = WS2812(pin=21, n=2, brightness=0.2)
    strip[1] = (100, 50, 250)
    assert strip[1] == (100, 50, 250)
    assert strip[-1] == (100, 50, 250)
    strip.show()
    assert _last_frame()[1][1] == (10, 20, 50)
    strip.brightness = 1.0
    strip.show()
    assert _last_frame()[1][1] == (50, 100, 250)


def test_clear_turns_everything_off_now():
    strip = WS2812(pin=21, n=8)
    strip.fill((255, 255, 255))
    strip.clear()
    assert _last_frame()[1] == [(0, 0, 0)] * 8
    assert len(strip) == 8


def test_bad_colours_indices_and_brightness_are_refused_with_the_valid_range():
    strip = WS2812(pin=21, n=8)
    with raises(ValueError, "0..255"):
        strip[0] = (256, 0, 0)
    with raises(ValueError, "(r, g, b)"):
        strip[0] = (1, 2)
    with raises(IndexError, "0..7"):
        strip[8] = (0, 0, 0)
    with raises(ValueError, "0.0..1.0"):
        strip.brightness = 1.5


def test_the_data_pin_is_claimed():
    WS2812(pin=21)
    with raises(pins.ReservedPinError, "GPIO 21"):
        WS2812(pin=21)
