"""MicroPython's `neopixel` (the frozen module of the ESP32 port): a GRB(W) byte buffer sent with
`machine.bitstream` on write(), so whatever `machine` is installed sees the bytes a WS2812 gets."""

# WS2812 bit timings (high-0, low-0, high-1, low-1) in ns for 800 kHz and 400 kHz parts.
_TIMING_800KHZ = (400, 850, 800, 450)
_TIMING_400KHZ = (800, 1700, 1600, 900)


class NeoPixel:
    ORDER = (1, 0, 2, 3)  # the chip wants green first

    def __init__(self, pin, n, bpp=3, timing=1):
        self.pin = pin
        self.n = n
        self.bpp = bpp
        self.buf = bytearray(n * bpp)
        self.pin.init(pin.OUT)
        # 1 for 800 kHz, 0 for 400 kHz, or the caller's own (high_0, low_0, high_1, low_1) in ns.
        if isinstance(timing, int):
            timing = _TIMING_800KHZ if timing else _TIMING_400KHZ
        self.timing = timing

    def __len__(self):
        return self.n

    def __setitem__(self, index, value):
        offset = index * self.bpp
        for channel in range(self.bpp):
            self.buf[offset + self.ORDER[channel]] = value[channel]

    def __getitem__(self, index):
        offset = index * self.bpp
        return tuple(self.buf[offset + self.ORDER[channel]] for channel in range(self.bpp))

    def fill(self, value):
        for index in range(self.n):
            self[index] = value

    def write(self):
        from machine import bitstream  # the installed one: the simulated hub's, or a test's board

        bitstream(self.pin, 0, self.timing, self.buf)
