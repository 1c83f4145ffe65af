"""MicroPython's `framebuf` for CPython runs, MONO_VLSB only (the SSD1306 layout).

MicroPython has the real module built in, and the runtime tests use it there.
Byte layout, clipping and drawing follow the built-in: byte (y // 8) * stride
+ x holds 8 vertical pixels, bit 0 at the top. text() draws a stand-in glyph
in each 8x8 cell (the built-in font's bitmaps are not reproduced): columns
0-5, rows 0-6 of the cell, distinct per character, nothing for a space, so
tests can check where text lands but not what it spells.
"""

MONO_VLSB = 0
RGB565 = 1
GS4_HMSB = 2
MONO_HLSB = 3
MONO_HMSB = 4
GS2_HMSB = 5
GS8 = 6


class FrameBuffer:
    def __init__(self, buffer, width, height, format, stride=None):
        if format != MONO_VLSB:
            raise ValueError("the test framebuf only implements MONO_VLSB")
        self._buf = buffer
        self.width = width
        self.height = height
        self._stride = width if stride is None else stride
        if len(buffer) < ((height + 7) // 8) * self._stride:
            raise ValueError("buffer too small")

    def pixel(self, x, y, c=None):
        if not (0 <= x < self.width and 0 <= y < self.height):
            return None
        index = (y >> 3) * self._stride + x
        bit = 1 << (y & 7)
        if c is None:
            return 1 if self._buf[index] & bit else 0
        if c:
            self._buf[index] |= bit
        else:
            self._buf[index] &= ~bit & 0xFF
        return None

    def fill(self, c):
        value = 0xFF if c else 0x00
        for i in range(((self.height + 7) // 8) * self._stride):
            self._buf[i] = value

    def fill_rect(self, x, y, w, h, c):
        for yy in range(max(0, y), min(self.height, y + h)):
            for xx in range(max(0, x), min(self.width, x + w)):
                self.pixel(xx, yy, c)

    def hline(self, x, y, w, c):
        self.fill_rect(x, y, w, 1, c)

    def vline(self, x, y, h, c):
        self.fill_rect(x, y, 1, h, c)

    def rect(self, x, y, w, h, c, f=False):
        if f:
            self.fill_rect(x, y, w, h, c)
            return
        self.hline(x, y, w, c)
        self.hline(x, y + h - 1, w, c)
        self.vline(x, y, h, c)
        self.vline(x + w - 1, y, h, c)

    def line(self, x1, y1, x2, y2, c):
        dx, dy = abs(x2 - x1), -abs(y2 - y1)
        sx = 1 if x1 < x2 else -1
        sy = 1 if y1 < y2 else -1
        err = dx + dy
        while True:
            self.pixel(x1, y1, c)
            if x1 == x2 and y1 == y2:
                return
            e2 = 2 * err
            if e2 >= dy:
                err += dy
                x1 += sx
            if e2 <= dx:
                err += dx
                y1 += sy

    def text(self, s, x, y, c=1):
        for ch in s:
            code = ord(ch)
            if code != 32:
                for col in range(6):
                    column = 0x7F if (code >> col) & 1 else 0x41
                    for row in range(7):
                        if column >> row & 1:
                            self.pixel(x + col, y + row, c)
            x += 8

    def scroll(self, xstep, ystep):
        old = [[self.pixel(x, y) for x in range(self.width)] for y in range(self.height)]
        for y in range(self.height):
            for x in range(self.width):
                sx, sy = x - xstep, y - ystep
                if 0 <= sx < self.width and 0 <= sy < self.height:
                    self.pixel(x, y, old[sy][sx])
