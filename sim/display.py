"""An SSD1306 OLED controller on the simulated hub's I2C bus: what the program's display shows.

The model speaks the controller's I2C protocol (datasheet 8.1.5): each write starts with a control
byte, 0x00 for a stream of commands, 0x40 for display RAM. It keeps the 128 x 64 RAM (8 pages of
one byte per column, bit 0 at the top), the column/page window and horizontal addressing that a
refresh streams into, the on/off, invert and contrast settings, and the segment remap / COM scan
direction, so `picture()` gives what a person would see on the panel (`lit(x, y)`, `rows()`).
"""

from dataclasses import dataclass

COLUMNS = 128
PAGES = 8

# Commands followed by argument bytes (everything else in the stream is a single byte).
_ARGUMENTS = {0x20: 1, 0x21: 2, 0x22: 2, 0x26: 6, 0x27: 6, 0x29: 5, 0x2A: 5, 0x81: 1, 0x8D: 1, 0xA3: 2}
_ARGUMENTS.update({0xA8: 1, 0xD3: 1, 0xD5: 1, 0xD9: 1, 0xDA: 1, 0xDB: 1})


class SSD1306Model:
    """The controller at one I2C address; `width` x `height` is the panel glued to it."""

    def __init__(self, width=128, height=64):
        self.width = width
        self.height = height
        self.ram = bytearray(COLUMNS * PAGES)
        self.on = False
        self.inverted = False
        self.contrast = 0x7F
        self.segment_remap = False
        self.com_reversed = False
        self.writes = 0  # display RAM transfers (show() calls), for a viewer that redraws on change
        self._window = [0, COLUMNS - 1, 0, PAGES - 1]
        self._column = 0
        self._page = 0

    # --- the bus side ---------------------------------------------------------------------

    def write(self, data):
        data = bytes(data)
        if not data:
            return
        control, payload = data[0], data[1:]
        if control & 0x40:
            self._ram_write(payload)
        else:
            self._commands(payload)

    def read(self, nbytes):
        return bytes(nbytes)  # the I2C interface has no reads; the status byte reads 0

    def write_mem(self, reg, data, addrsize=8):
        self.write(bytes((reg,)) + bytes(data))

    def read_mem(self, reg, nbytes, addrsize=8):
        return self.read(nbytes)

    def _commands(self, stream):
        i = 0
        while i < len(stream):
            code = stream[i]
            count = _ARGUMENTS.get(code, 0)
            args = stream[i + 1 : i + 1 + count]
            i += 1 + count
            if code == 0x21 and len(args) == 2:
                self._window[0:2] = [args[0] & 0x7F, args[1] & 0x7F]
                self._column = self._window[0]
            elif code == 0x22 and len(args) == 2:
                self._window[2:4] = [args[0] & 0x07, args[1] & 0x07]
                self._page = self._window[2]
            elif code == 0x81 and args:
                self.contrast = args[0]
            elif code in (0xAE, 0xAF):
                self.on = code == 0xAF
            elif code in (0xA6, 0xA7):
                self.inverted = code == 0xA7
            elif code in (0xA0, 0xA1):
                self.segment_remap = code == 0xA1
            elif code in (0xC0, 0xC8):
                self.com_reversed = code == 0xC8

    def _ram_write(self, payload):
        first_column, last_column, first_page, last_page = self._window
        for byte in payload:
            self.ram[self._page * COLUMNS + self._column] = byte
            if self._column < last_column:
                self._column += 1
            else:
                self._column = first_column
                self._page = self._page + 1 if self._page < last_page else first_page
        self.writes += 1

    # --- what the panel shows ---------------------------------------------------------------

    def picture(self):
        """What the panel shows now, as an immutable copy (cheap: for a viewer on another thread)."""
        return Picture(
            bytes(self.ram),
            self.width,
            self.height,
            self.on,
            self.inverted,
            self.segment_remap,
            self.com_reversed,
            self.writes,
        )

    def lit(self, x, y):
        return self.picture().lit(x, y)

    def rows(self, lit="#", dark="."):
        return self.picture().rows(lit, dark)


@dataclass(frozen=True)
class Picture:
    ram: bytes
    width: int
    height: int
    on: bool
    inverted: bool
    segment_remap: bool
    com_reversed: bool
    writes: int

    def lit(self, x, y):
        """Whether the panel's pixel (x, y) is lit, (0, 0) at the top-left as the driver draws it."""
        if not self.on or not (0 <= x < self.width and 0 <= y < self.height):
            return False
        offset = (COLUMNS - self.width) // 2  # a narrow panel sits in the middle of the columns
        column = offset + x if self.segment_remap else COLUMNS - 1 - offset - x
        row = y if self.com_reversed else self.height - 1 - y
        bit = (self.ram[(row >> 3) * COLUMNS + column] >> (row & 7)) & 1
        return bool(bit) != self.inverted

    def rows(self, lit="#", dark="."):
        """The picture as text, one string per pixel row."""
        return [
            "".join(lit if self.lit(x, y) else dark for x in range(self.width)) for y in range(self.height)
        ]

    def block_text(self):
        """The picture in half-block characters, two pixel rows per line (for a text panel)."""
        glyphs = {(True, True): "\u2588", (True, False): "\u2580", (False, True): "\u2584"}
        lines = []
        for y in range(0, self.height, 2):
            lines.append(
                "".join(glyphs.get((self.lit(x, y), self.lit(x, y + 1)), " ") for x in range(self.width))
            )
        return "\n".join(lines)
