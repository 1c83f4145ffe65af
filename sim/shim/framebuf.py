"""MicroPython's `framebuf` for the simulated hub: the built-in module, in Python.

A program drawing on an SSD1306 (or any display driver built on FrameBuffer) runs unchanged in
the simulator. Pixel layouts, clipping, the line, ellipse and polygon rasterisers, blit with a
transparent key and palette, scroll, and text in the built-in 8x8 font all follow MicroPython's
extmod/modframebuf.c (MIT licence, Damien P. George), whose font (font_petme128_8x8, ASCII 32-127,
one byte per column, bit 0 at the top) is carried below.
"""

MONO_VLSB = 0
RGB565 = 1
GS4_HMSB = 2
MONO_HLSB = 3
MONO_HMSB = 4
GS2_HMSB = 5
GS8 = 6
MVLSB = MONO_VLSB

_BITS = {MONO_VLSB: 1, RGB565: 16, GS4_HMSB: 4, MONO_HLSB: 1, MONO_HMSB: 1, GS2_HMSB: 2, GS8: 8}

_FONT_8X8 = bytes.fromhex(
    "00000000000000000000004f4f0000000007070000070700147f7f14147f7f1400242e6b6b3a1200006333180c666300"
    "00327f4d4d777250000000040603010000001c3e63410000000041633e1c0000082a3e1c1c3e2a080008083e3e080800"
    "000080e0600000000008080808080800000000606000000000406030180c0602003e7f49457f3e000040447f7f404000"
    "00627351494f460000226349497f360000181814167f7f1000276745457d3900003e7f49497b3200000303797d070300"
    "00367f49497f360000266f49497f3e000000002424000000000080e46400000000081c36634141000014141414141400"
    "00414163361c080000020351590f0600003e7f414d4f2e00007c7e0b0b7e7c00007f7f49497f3600003e7f4141632200"
    "007f7f41633e1c00007f7f4949414100007f7f0909010100003e7f41497b3a00007f7f08087f7f000000417f7f410000"
    "002060417f3f0100007f7f1c36634100007f7f4040404000007f7f060c067f7f007f7f0e1c7f7f00003e7f41417f3e00"
    "007f7f09090f0600001e3f21617f5e00007f7f19396f460000266f49497b32000001017f7f010100003f7f40407f3f00"
    "001f3f60603f1f00007f7f3018307f7f0063771c1c77630000070f78780f0700006171594d47430000007f7f41410000"
    "0002060c18306040000041417f7f000000080c06060c0800c0c0c0c0c0c0c0c0000001030604000000207454547c7800"
    "007f7f44447c380000387c44446c280000387c44447f7f0000387c54545c580000087e7f090302000098bca4a4fc7c00"
    "007f7f04047c78000000007d7d0000000040c08080fd7d00007f7f30386c44000000417f7f400000007c7c1830187c7c"
    "007c7c04047c780000387c44447c380000fcfc24243c180000183c2424fcfc00007c7c04040c080000485c5454742000"
    "04043f7f44642000003c7c40407c3c00001c3c60603c1c00001c7c3018307c1c00446c38386c4400009cbca0a0fc7c00"
    "004464745c4c44000008083e77414100000000ffff000000004141773e0808000002030103020301aa55aa55aa55aa55"
)


class FrameBuffer:
    """FrameBuffer(buffer, width, height, format, stride=width), drawing into `buffer` in place."""

    def __init__(self, buffer, width, height, format, stride=None):
        stride = width if stride is None else stride
        if width < 1 or height < 1 or width > 0xFFFF or height > 0xFFFF or stride > 0xFFFF or stride < width:
            raise ValueError
        if format not in _BITS:
            raise ValueError("invalid format")
        bpp = _BITS[format]
        height_required, width_required, strides_required = height, width, height - 1
        if format == MONO_VLSB:
            height_required = (height + 7) & ~7
            strides_required = height_required - 8
        elif format in (MONO_HLSB, MONO_HMSB):
            stride = (stride + 7) & ~7
            width_required = (width + 7) & ~7
        elif format == GS2_HMSB:
            stride = (stride + 3) & ~3
            width_required = (width + 3) & ~3
        elif format == GS4_HMSB:
            stride = (stride + 1) & ~1
            width_required = (width + 1) & ~1
        view = memoryview(buffer)
        if view.ndim != 1 or view.itemsize != 1:
            view = view.cast("B")
        needed = (
            (strides_required * stride + (height_required - strides_required) * width_required) * bpp // 8
        )
        if needed > len(view):
            raise ValueError
        self._buf = view
        self._buffer = buffer
        self.width = width
        self.height = height
        self.format = format
        self.stride = stride

    # --- one pixel, per format (x, y already inside the frame) ---------------------------------

    def _set(self, x, y, c):
        buf, fmt = self._buf, self.format
        if fmt == MONO_VLSB:
            i, bit = (y >> 3) * self.stride + x, 1 << (y & 7)
            buf[i] = (buf[i] | bit) if c else (buf[i] & ~bit & 0xFF)
        elif fmt == MONO_HLSB or fmt == MONO_HMSB:
            i = (x + y * self.stride) >> 3
            bit = 1 << ((x & 7) if fmt == MONO_HMSB else 7 - (x & 7))
            buf[i] = (buf[i] | bit) if c else (buf[i] & ~bit & 0xFF)
        elif fmt == RGB565:
            i = 2 * (x + y * self.stride)
            buf[i], buf[i + 1] = c & 0xFF, (c >> 8) & 0xFF
        elif fmt == GS2_HMSB:
            i, shift = (x + y * self.stride) >> 2, (x & 3) << 1
            buf[i] = ((c & 3) << shift) | (buf[i] & ~(3 << shift) & 0xFF)
        elif fmt == GS4_HMSB:
            i = (x + y * self.stride) >> 1
            buf[i] = ((c & 0x0F) | (buf[i] & 0xF0)) if x % 2 else (((c << 4) & 0xF0) | (buf[i] & 0x0F))
        else:
            buf[x + y * self.stride] = c & 0xFF

    def _get(self, x, y):
        buf, fmt = self._buf, self.format
        if fmt == MONO_VLSB:
            return (buf[(y >> 3) * self.stride + x] >> (y & 7)) & 1
        if fmt == MONO_HLSB or fmt == MONO_HMSB:
            offset = (x & 7) if fmt == MONO_HMSB else 7 - (x & 7)
            return (buf[(x + y * self.stride) >> 3] >> offset) & 1
        if fmt == RGB565:
            i = 2 * (x + y * self.stride)
            return buf[i] | (buf[i + 1] << 8)
        if fmt == GS2_HMSB:
            return (buf[(x + y * self.stride) >> 2] >> ((x & 3) << 1)) & 3
        if fmt == GS4_HMSB:
            pair = buf[(x + y * self.stride) >> 1]
            return pair & 0x0F if x % 2 else pair >> 4
        return buf[x + y * self.stride]

    def _set_checked(self, x, y, c, mask=1):
        if mask and 0 <= x < self.width and 0 <= y < self.height:
            self._set(x, y, c)

    def _fill_rect(self, x, y, w, h, c):
        if h < 1 or w < 1 or x + w <= 0 or y + h <= 0 or y >= self.height or x >= self.width:
            return
        xend, yend = min(self.width, x + w), min(self.height, y + h)
        x, y = max(x, 0), max(y, 0)
        for yy in range(y, yend):
            for xx in range(x, xend):
                self._set(xx, yy, c)

    # --- drawing -----------------------------------------------------------------------------

    def fill(self, c):
        self._fill_rect(0, 0, self.width, self.height, c)

    def fill_rect(self, x, y, w, h, c):
        self._fill_rect(x, y, w, h, c)

    def pixel(self, x, y, c=None):
        if 0 <= x < self.width and 0 <= y < self.height:
            if c is None:
                return self._get(x, y)
            self._set(x, y, c)
        return None

    def hline(self, x, y, w, c):
        self._fill_rect(x, y, w, 1, c)

    def vline(self, x, y, h, c):
        self._fill_rect(x, y, 1, h, c)

    def rect(self, x, y, w, h, c, f=False):
        if f:
            self._fill_rect(x, y, w, h, c)
        else:
            self._fill_rect(x, y, w, 1, c)
            self._fill_rect(x, y + h - 1, w, 1, c)
            self._fill_rect(x, y, 1, h, c)
            self._fill_rect(x + w - 1, y, 1, h, c)

    def line(self, x1, y1, x2, y2, c):
        dx, sx = (x2 - x1, 1) if x2 - x1 > 0 else (x1 - x2, -1)
        dy, sy = (y2 - y1, 1) if y2 - y1 > 0 else (y1 - y2, -1)
        steep = dy > dx
        if steep:
            x1, y1, dx, dy, sx, sy = y1, x1, dy, dx, sy, sx
        e = 2 * dy - dx
        for _ in range(dx):
            if steep:
                self._set_checked(y1, x1, c)
            else:
                self._set_checked(x1, y1, c)
            while e >= 0:
                y1 += sy
                e -= 2 * dx
            x1 += sx
            e += 2 * dy
        self._set_checked(x2, y2, c)

    def ellipse(self, cx, cy, xr, yr, c, f=False, m=0x0F):
        mask = (0x10 if f else 0) | (m & 0x0F)
        if xr == 0 and yr == 0:
            self._set_checked(cx, cy, c, mask & 0x0F)
            return
        two_a, two_b = 2 * xr * xr, 2 * yr * yr
        x, y = xr, 0
        xchange, ychange = yr * yr * (1 - 2 * xr), xr * xr
        error, stop_x, stop_y = 0, two_b * xr, 0
        while stop_x >= stop_y:
            self._ellipse_points(cx, cy, x, y, c, mask)
            y += 1
            stop_y += two_a
            error += ychange
            ychange += two_a
            if 2 * error + xchange > 0:
                x -= 1
                stop_x -= two_b
                error += xchange
                xchange += two_b
        x, y = 0, yr
        xchange, ychange = yr * yr, xr * xr * (1 - 2 * yr)
        error, stop_x, stop_y = 0, 0, two_a * yr
        while stop_x <= stop_y:
            self._ellipse_points(cx, cy, x, y, c, mask)
            x += 1
            stop_x += two_b
            error += xchange
            xchange += two_b
            if 2 * error + ychange > 0:
                y -= 1
                stop_y -= two_a
                error += ychange
                ychange += two_a

    def _ellipse_points(self, cx, cy, x, y, c, mask):
        if mask & 0x10:
            if mask & 1:
                self._fill_rect(cx, cy - y, x + 1, 1, c)
            if mask & 2:
                self._fill_rect(cx - x, cy - y, x + 1, 1, c)
            if mask & 4:
                self._fill_rect(cx - x, cy + y, x + 1, 1, c)
            if mask & 8:
                self._fill_rect(cx, cy + y, x + 1, 1, c)
        else:
            self._set_checked(cx + x, cy - y, c, mask & 1)
            self._set_checked(cx - x, cy - y, c, mask & 2)
            self._set_checked(cx - x, cy + y, c, mask & 4)
            self._set_checked(cx + x, cy + y, c, mask & 8)

    def poly(self, x, y, coords, c, f=False):
        """The closed polygon through `coords` (an array of x0, y0, x1, y1, ...), offset by (x, y)."""
        points = list(coords)
        n = len(points) // 2
        if n == 0:
            return
        if not f:
            px1, py1 = points[0], points[1]
            for i in range(n - 1, -1, -1):
                px2, py2 = points[2 * i], points[2 * i + 1]
                self.line(x + px1, y + py1, x + px2, y + py2, c)
                px1, py1 = px2, py2
            return
        ys = [points[2 * i + 1] for i in range(n)]
        for row in range(min(ys), max(ys) + 1):
            # The scan line's crossings with the edges (the bottom pixel of each edge left out, so a
            # vertex shared by two edges counts once), filled pairwise; local minima by hand.
            nodes = []
            px1, py1 = points[0], points[1]
            for i in range(n - 1, -1, -1):
                px2, py2 = points[2 * i], points[2 * i + 1]
                if py1 != py2 and ((py1 > row >= py2) or (py1 <= row < py2)):
                    nodes.append(_cdiv(32 * px1 + _cdiv(32 * (px2 - px1) * (row - py1), py2 - py1) + 16, 32))
                elif row == max(py1, py2):
                    if py1 < py2:
                        self._set_checked(x + px2, y + py2, c)
                    elif py2 < py1:
                        self._set_checked(x + px1, y + py1, c)
                    else:
                        self.line(x + px1, y + py1, x + px2, y + py2, c)
                px1, py1 = px2, py2
            nodes.sort()
            for i in range(0, len(nodes) - 1, 2):
                self._fill_rect(x + nodes[i], y + row, nodes[i + 1] - nodes[i] + 1, 1, c)

    def text(self, s, x0, y0, c=1):
        for ch in s:
            code = ord(ch)
            if code < 32 or code > 127:
                code = 127
            glyph = _FONT_8X8[(code - 32) * 8 : (code - 31) * 8]
            for column in glyph:
                if 0 <= x0 < self.width:
                    y = y0
                    while column:
                        if column & 1 and 0 <= y < self.height:
                            self._set(x0, y, c)
                        column >>= 1
                        y += 1
                x0 += 1

    def scroll(self, xstep, ystep):
        if xstep < 0:
            if -xstep >= self.width:
                return
            xs = range(0, self.width + xstep)
        else:
            if xstep >= self.width:
                return
            xs = range(self.width - 1, xstep - 1, -1)
        if ystep < 0:
            if -ystep >= self.height:
                return
            ys = range(0, self.height + ystep)
        else:
            if ystep >= self.height:
                return
            ys = range(self.height - 1, ystep - 1, -1)
        for y in ys:
            for x in xs:
                self._set(x, y, self._get(x - xstep, y - ystep))

    def blit(self, fbuf, x, y, key=-1, palette=None):
        source = fbuf if isinstance(fbuf, FrameBuffer) else FrameBuffer(*fbuf)
        if palette is not None and not isinstance(palette, FrameBuffer):
            palette = FrameBuffer(*palette)
        if x >= self.width or y >= self.height or -x >= source.width or -y >= source.height:
            return
        x1, y1 = max(0, -x), max(0, -y)
        for y0 in range(max(0, y), min(self.height, y + source.height)):
            cx1 = x1
            for x0 in range(max(0, x), min(self.width, x + source.width)):
                c = source._get(cx1, y1)
                if palette is not None:
                    c = palette._get(c, 0)
                if c != key:
                    self._set(x0, y0, c)
                cx1 += 1
            y1 += 1


def _cdiv(a, b):
    """C's integer division (truncating towards zero), as the built-in module computes."""
    q = abs(a) // abs(b)
    return -q if (a < 0) != (b < 0) else q


def FrameBuffer1(buffer, width, height, stride=None):
    """The old MONO_VLSB-only constructor, kept by MicroPython."""
    return FrameBuffer(buffer, width, height, MONO_VLSB, stride)
