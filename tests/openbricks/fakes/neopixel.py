"""A fake of MicroPython's `neopixel` module that talks to the fake wire.

Like the real module it keeps a GRB(W) byte buffer and sends it with
`machine.bitstream` on write(), so tests read the bytes a WS2812 would
receive from `machine.board.bitstreams`.
"""

from . import machine

# WS2812 bit timings (high-0, low-0, high-1, low-1) in ns for 800 kHz and 400 kHz parts.
_TIMING_800KHZ = (400, 850, 800, 450)
_TIMING_400KHZ = (800, 1700, 1600, 900)
_ORDER = (1, 0, 2, 3)  # the chip wants green first


class NeoPixel:
    def __init__(self, pin, n, bpp=3, timing=1):
        self.pin = pin
        self.n = n
        self.bpp = bpp
        self.buf = bytearray(n * bpp)
        if isinstance(timing, int):
            timing = _TIMING_800KHZ if timing else _TIMING_400KHZ
        self.timing = timing

    def __len__(self):
        return self.n

    def __setitem__(self, index, value):
        offset = index * self.bpp
        for channel in range(self.bpp):
            self.buf[offset + _ORDER[channel]] = value[channel]

    def __getitem__(self, index):
        offset = index * self.bpp
        return tuple(self.buf[offset + _ORDER[channel]] for channel in range(self.bpp))

    def fill(self, value):
        for index in range(self.n):
            self[index] = value

    def write(self):
        machine.bitstream(self.pin, 0, self.timing, self.buf)
