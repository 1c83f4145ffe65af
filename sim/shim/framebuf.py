"""MicroPython's `framebuf` for the simulated hub, so a program drawing on an SSD1306 (or any
display driver built on FrameBuffer) runs unchanged in the simulator.

The API, pixel layouts and clipping are the documented ones, because drivers write the buffer
straight to the display. The shapes come from textbook rasterisers (Bresenham lines, the
midpoint ellipse, an even-odd scanline polygon fill), so a line or curve can differ by a pixel
from a real hub's; programs don't depend on that. Text keeps the documented 8x8 cells; the glyphs
are drawn from Pillow's default font on first use, so the panel shows readable characters.
"""

MONO_VLSB = 0
RGB565 = 1
GS4_HMSB = 2
MONO_HLSB = 3
MONO_HMSB = 4
GS2_HMSB = 5
GS8 = 6
MVLSB = MONO_VLSB

# Row-packed formats: bits per pixel, and whether the leftmost pixel of a byte is its top bit.
_PACKED = {MONO_HLSB: (1, True), MONO_HMSB: (1, False), GS2_HMSB: (2, False), GS4_HMSB: (4, True)}
_FORMATS = (MONO_VLSB, RGB565, GS4_HMSB, MONO_HLSB, MONO_HMSB, GS2_HMSB, GS8)

CELL = 8  # text() puts each character in an 8x8 cell
_glyphs = None  # ASCII 32-126 -> 8 column bytes (bit 0 on top), built on first text()


class FrameBuffer:
    """FrameBuffer(buffer, width, height, format, stride=width), drawing into `buffer` in place."""

    def __init__(self, buffer, width, height, format, stride=None):
        if format not in _FORMATS:
            raise ValueError("invalid format")
        stride = width if stride is None else stride
        if not (0 < width <= 0xFFFF and 0 < height <= 0xFFFF and width <= stride <= 0xFFFF):
            raise ValueError("width, height and stride must be 1-65535, with stride >= width")
        if format in _PACKED:
            per_byte = 8 // _PACKED[format][0]
            stride = -(-stride // per_byte) * per_byte  # rows start on a byte boundary
        view = memoryview(buffer)
        if view.ndim != 1 or view.itemsize != 1:
            view = view.cast("B")
        if len(view) < _bytes_needed(format, width, height, stride):
            raise ValueError("buffer too small")
        self._buf = view
        self._buffer = buffer
        self.width = width
        self.height = height
        self.format = format
        self.stride = stride

    # --- single pixels (callers keep x, y inside the frame) -----------------------------------

    def _set(self, x, y, c):
        fmt, buf = self.format, self._buf
        if fmt == GS8:
            buf[y * self.stride + x] = c & 0xFF
        elif fmt == RGB565:
            at = 2 * (y * self.stride + x)
            buf[at : at + 2] = (c & 0xFFFF).to_bytes(2, "little")
        else:
            at, shift, mask = self._locate(x, y)
            buf[at] = (buf[at] & ~(mask << shift) & 0xFF) | ((c & mask) << shift)

    def _get(self, x, y):
        fmt, buf = self.format, self._buf
        if fmt == GS8:
            return buf[y * self.stride + x]
        if fmt == RGB565:
            at = 2 * (y * self.stride + x)
            return int.from_bytes(buf[at : at + 2], "little")
        at, shift, mask = self._locate(x, y)
        return (buf[at] >> shift) & mask

    def _locate(self, x, y):
        """(byte index, bit shift, value mask) of a pixel in a format of under 8 bits."""
        if self.format == MONO_VLSB:
            return (y // 8) * self.stride + x, y % 8, 1
        bits, leftmost_high = _PACKED[self.format]
        per_byte = 8 // bits
        slot = x % per_byte
        if leftmost_high:
            slot = per_byte - 1 - slot
        return (y * self.stride + x) // per_byte, slot * bits, (1 << bits) - 1

    def _plot(self, x, y, c):
        if 0 <= x < self.width and 0 <= y < self.height:
            self._set(x, y, c)

    def _span(self, x0, x1, y, c):
        """The row y from x0 to x1 inclusive, clipped."""
        if 0 <= y < self.height:
            for x in range(max(min(x0, x1), 0), min(max(x0, x1), self.width - 1) + 1):
                self._set(x, y, c)

    # --- drawing -----------------------------------------------------------------------------

    def fill(self, c):
        self.fill_rect(0, 0, self.width, self.height, c)

    def fill_rect(self, x, y, w, h, c):
        if w > 0:
            for row in range(max(y, 0), min(y + h, self.height)):
                self._span(x, x + w - 1, row, c)

    def pixel(self, x, y, c=None):
        if not (0 <= x < self.width and 0 <= y < self.height):
            return None
        if c is None:
            return self._get(x, y)
        self._set(x, y, c)
        return None

    def hline(self, x, y, w, c):
        self.fill_rect(x, y, w, 1, c)

    def vline(self, x, y, h, c):
        self.fill_rect(x, y, 1, h, c)

    def rect(self, x, y, w, h, c, f=False):
        if f:
            self.fill_rect(x, y, w, h, c)
            return
        self.fill_rect(x, y, w, 1, c)
        self.fill_rect(x, y + h - 1, w, 1, c)
        self.fill_rect(x, y, 1, h, c)
        self.fill_rect(x + w - 1, y, 1, h, c)

    def line(self, x1, y1, x2, y2, c):
        """Bresenham's line, both ends included."""
        dx, dy = abs(x2 - x1), -abs(y2 - y1)
        step_x, step_y = (1 if x2 > x1 else -1), (1 if y2 > y1 else -1)
        error = dx + dy
        while True:
            self._plot(x1, y1, c)
            if x1 == x2 and y1 == y2:
                return
            twice = 2 * error
            if twice >= dy:
                error += dy
                x1 += step_x
            if twice <= dx:
                error += dx
                y1 += step_y

    def ellipse(self, cx, cy, xr, yr, c, f=False, m=0x0F):
        """Midpoint ellipse; bit n of `m` enables quadrant n+1 (counter-clockwise from top right)."""
        for x, y in _quarter_ellipse(abs(xr), abs(yr)):
            for bit, sx, sy in ((1, 1, -1), (2, -1, -1), (4, -1, 1), (8, 1, 1)):
                if m & bit:
                    if f:
                        self._span(cx, cx + sx * x, cy + sy * y, c)
                    else:
                        self._plot(cx + sx * x, cy + sy * y, c)

    def poly(self, x, y, coords, c, f=False):
        """The closed polygon through `coords` (an array of x0, y0, x1, y1, ...), offset by (x, y)."""
        values = list(coords)
        corners = [(x + values[i], y + values[i + 1]) for i in range(0, len(values) - 1, 2)]
        if not corners:
            return
        edges = list(zip(corners, corners[1:] + corners[:1], strict=True))
        if f:
            rows = [cy for _, cy in corners]
            for row in range(max(min(rows), 0), min(max(rows), self.height - 1) + 1):
                crossings = sorted(_crossing(a, b, row) for a, b in edges if _crosses(a, b, row))
                for left, right in zip(crossings[::2], crossings[1::2], strict=False):
                    self._span(left, right, row, c)
        for (ax, ay), (bx, by) in edges:  # the outline, so edges and corners are always drawn
            self.line(ax, ay, bx, by, c)

    def text(self, s, x, y, c=1):
        glyphs = _glyph_table()
        for ch in str(s):
            for column in glyphs.get(ch, glyphs[None]):
                if 0 <= x < self.width:
                    for row in range(CELL):
                        if column >> row & 1:
                            self._plot(x, y + row, c)
                x += 1

    def scroll(self, xstep, ystep):
        """Shift the contents; the uncovered strip keeps its old pixels, as on a real hub."""
        w, h = self.width, self.height
        if abs(xstep) >= w or abs(ystep) >= h:
            return
        before = [[self._get(px, py) for px in range(w)] for py in range(h)]
        for py in range(max(ystep, 0), min(h + ystep, h)):
            for px in range(max(xstep, 0), min(w + xstep, w)):
                self._set(px, py, before[py - ystep][px - xstep])

    def blit(self, fbuf, x, y, key=-1, palette=None):
        """Copy `fbuf` (a FrameBuffer or (buffer, width, height, format[, stride])) to (x, y).

        With a palette, source values index its first row; `key` (after the palette) is transparent.
        """
        source = fbuf if isinstance(fbuf, FrameBuffer) else FrameBuffer(*fbuf)
        if palette is not None and not isinstance(palette, FrameBuffer):
            palette = FrameBuffer(*palette)
        for sy in range(max(0, -y), min(source.height, self.height - y)):
            for sx in range(max(0, -x), min(source.width, self.width - x)):
                value = source._get(sx, sy)
                if palette is not None:
                    value = palette._get(value, 0) if value < palette.width else 0
                if value != key:
                    self._set(x + sx, y + sy, value)


def FrameBuffer1(buffer, width, height, stride=None):
    """The old MONO_VLSB-only constructor, which MicroPython still accepts."""
    return FrameBuffer(buffer, width, height, MONO_VLSB, stride)


def _bytes_needed(format, width, height, stride):
    if format == MONO_VLSB:
        return ((height + 7) // 8 - 1) * stride + width
    if format in _PACKED:
        per_byte = 8 // _PACKED[format][0]
        return ((height - 1) * stride + width + per_byte - 1) // per_byte
    pixels = (height - 1) * stride + width
    return 2 * pixels if format == RGB565 else pixels


def _quarter_ellipse(a, b):
    """The points (x, y >= 0) of the midpoint ellipse with radii a, b, in the first quadrant."""
    if a == 0 or b == 0:
        return [(x, 0) for x in range(a + 1)] + [(0, y) for y in range(b + 1)]
    points, a2, b2 = [], a * a, b * b
    x, y = 0, b
    # Region 1, where the slope is shallower than -1: step x, sometimes y. Decisions are scaled by 4.
    decision = 4 * b2 - 4 * a2 * b + a2
    while b2 * x < a2 * y:
        points.append((x, y))
        x += 1
        if decision < 0:
            decision += 4 * b2 * (2 * x + 1)
        else:
            y -= 1
            decision += 4 * b2 * (2 * x + 1) - 8 * a2 * y
    # Region 2: step y, sometimes x.
    decision = b2 * (2 * x + 1) ** 2 + 4 * a2 * (y - 1) ** 2 - 4 * a2 * b2
    while y >= 0:
        points.append((x, y))
        y -= 1
        if decision > 0:
            decision += 4 * a2 - 8 * a2 * y
        else:
            x += 1
            decision += 8 * b2 * x - 8 * a2 * y + 4 * a2
    return points


def _crosses(a, b, row):
    """Whether the edge a-b spans scan row `row` (lower end excluded, so a shared corner counts once)."""
    return min(a[1], b[1]) <= row < max(a[1], b[1])


def _crossing(a, b, row):
    """The x, to the nearest pixel, where edge a-b meets scan row `row`."""
    (ax, ay), (bx, by) = (a, b) if a[1] < b[1] else (b, a)
    numerator, denominator = 2 * (ax * (by - ay) + (bx - ax) * (row - ay)) + (by - ay), 2 * (by - ay)
    return numerator // denominator


def _glyph_table():
    global _glyphs
    if _glyphs is None:
        _glyphs = _draw_glyphs()
    return _glyphs


def _draw_glyphs():
    """ASCII 32-126 from Pillow's default font at 8 px, thresholded into 8x8 cells.

    At this size a few shapes (braces, say) threshold to the same pixels; such a glyph takes the
    nearest other threshold that keeps it apart, so every character reads as itself. Characters
    outside that range get an open box.
    """
    from PIL import Image, ImageDraw, ImageFont

    font = ImageFont.load_default(size=CELL)
    printable = "".join(chr(code) for code in range(32, 127))
    top = font.getbbox(printable)[1]
    glyphs, taken = {}, set()
    for ch in printable:
        cell = Image.new("L", (CELL, CELL), 0)
        ImageDraw.Draw(cell).text((0, -top), ch, fill=255, font=font)
        ink = cell.load()
        for threshold in _THRESHOLDS:
            columns = bytes(
                sum(1 << row for row in range(CELL) if ink[col, row] >= threshold) for col in range(CELL)
            )
            if ch == " " or (any(columns) and columns not in taken):
                break
        glyphs[ch] = columns
        taken.add(columns)
    glyphs[None] = bytes((0x00, 0x7E, 0x42, 0x42, 0x42, 0x42, 0x7E, 0x00))
    return glyphs


_THRESHOLDS = (64, 56, 72, 48, 80, 40, 96, 128)  # ink levels (of 255) counted as a lit pixel, best first
