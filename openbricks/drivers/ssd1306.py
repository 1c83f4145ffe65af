"""SSD1306 OLED on I2C (128x64 or 128x32 panels): buffered drawing, one-transaction refresh.

Drawing goes to a `framebuf.FrameBuffer` in RAM in the controller's own
layout (MONO_VLSB: one byte = 8 vertical pixels of a page), so `show()` is a
single I2C write of the whole buffer. text/pixel/fill/show/clear are
explicit; every other drawing call (rect, line, hline, vline, fill_rect,
scroll, blit, ...) goes straight to the frame buffer.

Wire protocol (datasheet section 8.1.5): each transfer starts with a control
byte, 0x00 = a stream of commands, 0x40 = GDDRAM data. The buffer keeps that
0x40 as its first byte, so a refresh sends it without copying the frame.
"""

import framebuf
from micropython import const

_DEFAULT_ADDR = const(0x3C)
_CONTROL_COMMANDS = const(0x00)
_CONTROL_DATA = const(0x40)

_SET_CONTRAST = const(0x81)
_DISPLAY_ALL_FROM_RAM = const(0xA4)
_NORMAL = const(0xA6)
_INVERT = const(0xA7)
_DISPLAY_OFF = const(0xAE)
_DISPLAY_ON = const(0xAF)
_SET_MEMORY_MODE = const(0x20)
_SET_COLUMNS = const(0x21)
_SET_PAGES = const(0x22)
_START_LINE_0 = const(0x40)
_SEGMENT_REMAP = const(0xA1)  # column 127 drives SEG0: upright on the common modules
_SET_MULTIPLEX = const(0xA8)
_COM_SCAN_REVERSED = const(0xC8)  # with the remap above, (0, 0) is the top-left corner
_SET_DISPLAY_OFFSET = const(0xD3)
_SET_COM_PINS = const(0xDA)
_SET_CLOCK = const(0xD5)
_SET_PRECHARGE = const(0xD9)
_SET_VCOMH = const(0xDB)
_CHARGE_PUMP = const(0x8D)
_ENODEV = const(19)


class SSD1306:
    """An SSD1306 panel of `width` x `height` pixels at I2C `addr` (0x3C, or 0x3D with SA0 high)."""

    def __init__(self, i2c, addr=_DEFAULT_ADDR, width=128, height=64):
        if width not in (64, 128) or height not in (32, 64):
            raise ValueError("SSD1306 panels are 128x64, 128x32, 64x64 or 64x32; got %dx%d" % (width, height))
        self._i2c = i2c
        self._addr = addr
        self.width = width
        self.height = height
        self._pages = height // 8
        # Narrow panels sit in the middle of the controller's 128 columns.
        self._column0 = (128 - width) // 2
        self._buf = bytearray(1 + width * self._pages)
        self._buf[0] = _CONTROL_DATA
        self._fb = framebuf.FrameBuffer(memoryview(self._buf)[1:], width, height, framebuf.MONO_VLSB)
        try:
            self._command(_DISPLAY_OFF)
        except OSError as e:
            raise OSError(
                _ENODEV,
                "no SSD1306 answers at I2C address 0x%02X (%s): check SDA/SCL/power; modules with SA0 "
                "strapped high are at addr=0x3D" % (addr, e),
            ) from None
        self._command(
            _SET_MEMORY_MODE, 0x00,  # horizontal: show() streams the pages in one go
            _START_LINE_0,
            _SEGMENT_REMAP,
            _SET_MULTIPLEX, height - 1,
            _COM_SCAN_REVERSED,
            _SET_DISPLAY_OFFSET, 0x00,
            _SET_COM_PINS, 0x02 if width > 2 * height else 0x12,
            _SET_CLOCK, 0x80,
            _SET_PRECHARGE, 0xF1,  # internal charge pump timing
            _SET_VCOMH, 0x30,
            _SET_CONTRAST, 0xFF,
            _DISPLAY_ALL_FROM_RAM,
            _NORMAL,
            _CHARGE_PUMP, 0x14,  # the panel has no external VCC: without the pump it stays dark
        )  # fmt: skip
        self.clear()
        self._command(_DISPLAY_ON)

    def _command(self, *codes):
        self._i2c.writeto(self._addr, bytes((_CONTROL_COMMANDS,) + codes))

    # -- drawing (buffered) -----------------------------------------------------------------------

    def text(self, s, x, y, c=1):
        """Draw `s` in the 8x8 font with its top-left at (x, y); c=1 lit, c=0 dark. Buffered."""
        self._fb.text(s, x, y, c)

    def pixel(self, x, y, c=None):
        """Set pixel (x, y) to c (1 lit / 0 dark), or return it when c is None. Buffered."""
        if c is None:
            return self._fb.pixel(x, y)
        self._fb.pixel(x, y, c)
        return None

    def fill(self, c):
        """Fill the whole buffer with c (1 lit / 0 dark)."""
        self._fb.fill(c)

    def __getattr__(self, name):
        # rect, line, hline, vline, fill_rect, scroll, blit, ...: the frame buffer's own methods.
        if name.startswith("_"):
            raise AttributeError(name)
        return getattr(self._fb, name)

    # -- the panel ---------------------------------------------------------------------------------

    def show(self):
        """Push the buffer to the panel in one transfer (nothing drawn appears before this)."""
        self._command(
            _SET_COLUMNS, self._column0, self._column0 + self.width - 1, _SET_PAGES, 0, self._pages - 1
        )
        self._i2c.writeto(self._addr, self._buf)

    def clear(self):
        """Blank the display now (fill 0 + show)."""
        self._fb.fill(0)
        self.show()

    def contrast(self, value):
        """Panel brightness 0..255."""
        if not 0 <= value <= 255:
            raise ValueError("SSD1306 contrast is 0..255, got %r" % (value,))
        self._command(_SET_CONTRAST, value)

    def invert(self, on):
        """Show lit pixels dark and dark ones lit (True), or normally (False)."""
        self._command(_INVERT if on else _NORMAL)

    def poweroff(self):
        """Switch the panel off (the buffer and the controller's RAM are kept)."""
        self._command(_DISPLAY_OFF)

    def poweron(self):
        """Switch the panel back on, showing what the controller's RAM holds."""
        self._command(_DISPLAY_ON)

    def __repr__(self):
        return "SSD1306(addr=0x%02X, %dx%d)" % (self._addr, self.width, self.height)
