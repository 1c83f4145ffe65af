"""WS2812 / WS2812B addressable RGB LEDs (sticks, rings, strips) on one data GPIO.

The 800 kHz wire protocol is MicroPython's built-in `neopixel`; this wrapper
adds what programs want on top: colours kept unscaled (so `strip[i]` reads
back what was assigned) and a global brightness applied only when the strip
is pushed, and buffered updates: assignments touch memory, `show()` sends
the whole strip in one transaction so an animation frame never flickers.
"""

from machine import Pin
from neopixel import NeoPixel

from openbricks import pins


class WS2812:
    """`n` WS2812/WS2812B LEDs on GPIO `pin`; `brightness` 0.0-1.0 scales every colour at show()."""

    def __init__(self, pin, n=8, brightness=0.2):
        if not isinstance(n, int) or n < 1:
            raise ValueError("WS2812 needs n >= 1 LEDs, got %r" % (n,))
        pins.claim(pin, "WS2812 data output", owner=self)
        self._pin = pin
        self._n = n
        self._colors = bytearray(3 * n)  # unscaled r, g, b per LED
        self._brightness = _check_brightness(brightness)
        self._np = NeoPixel(Pin(pin, Pin.OUT), n)

    def __len__(self):
        return self._n

    def _offset(self, index):
        if not isinstance(index, int) or not -self._n <= index < self._n:
            raise IndexError("WS2812 on GPIO %d has LEDs 0..%d, got %r" % (self._pin, self._n - 1, index))
        return 3 * (index % self._n)

    def __setitem__(self, index, color):
        offset = self._offset(index)
        r, g, b = _check_color(color)
        self._colors[offset] = r
        self._colors[offset + 1] = g
        self._colors[offset + 2] = b

    def __getitem__(self, index):
        offset = self._offset(index)
        return (self._colors[offset], self._colors[offset + 1], self._colors[offset + 2])

    @property
    def brightness(self):
        """Global scale 0.0-1.0, applied to the whole strip at the next show()."""
        return self._brightness

    @brightness.setter
    def brightness(self, value):
        self._brightness = _check_brightness(value)

    def show(self):
        """Push every buffered colour, scaled by `brightness`, in one wire transaction."""
        scale = self._brightness
        colors = self._colors
        np = self._np
        for i in range(self._n):
            o = 3 * i
            np[i] = (
                int(colors[o] * scale + 0.5),
                int(colors[o + 1] * scale + 0.5),
                int(colors[o + 2] * scale + 0.5),
            )
        np.write()

    def fill(self, color):
        """Set every LED to `color` (r, g, b) and push immediately."""
        r, g, b = _check_color(color)
        for o in range(0, 3 * self._n, 3):
            self._colors[o] = r
            self._colors[o + 1] = g
            self._colors[o + 2] = b
        self.show()

    def clear(self):
        """Every LED off, pushed immediately."""
        self.fill((0, 0, 0))

    def __repr__(self):
        return "WS2812(pin=%d, n=%d, brightness=%s)" % (self._pin, self._n, self._brightness)


def _check_color(color):
    try:
        r, g, b = color
        if 0 <= r <= 255 and 0 <= g <= 255 and 0 <= b <= 255:
            return int(r), int(g), int(b)
    except (TypeError, ValueError):
        pass
    raise ValueError("WS2812 colours are (r, g, b) tuples with each 0..255, got %r" % (color,))


def _check_brightness(value):
    if not 0.0 <= value <= 1.0:
        raise ValueError("WS2812 brightness is 0.0..1.0, got %r" % (value,))
    return value
