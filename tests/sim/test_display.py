"""An SSD1306 program runs in the simulator: the shim's framebuf lays out pixels as MicroPython's
built-in module does and draws text in 8x8 cells, and the OLED model on I2C0 shows what the
program pushed."""

import pytest

from openbricks_sim.shim import Shim
from openbricks_sim.shim import framebuf as sim_framebuf
from openbricks_sim.simulation import Simulation


@pytest.fixture
def hub():
    sim = Simulation("empty", "st3032", seed=0, epoch_ms=0)
    with Shim(sim):
        yield sim
    sim.close()


PRINTABLE = "".join(chr(code) for code in range(32, 127))


def glyph_rows(char):
    """The 8x8 cell the shim's framebuf draws for `char`, as '#'/'.' rows."""
    cell = sim_framebuf.FrameBuffer(bytearray(8), 8, 8, sim_framebuf.MONO_VLSB)
    cell.text(char, 0, 0, 1)
    return ["".join("#" if cell.pixel(x, y) else "." for x in range(8)) for y in range(8)]


def test_text_drawn_on_the_oled_appears_on_the_panel_in_the_framebuf_font(hub):
    from machine import I2C, Pin

    from openbricks.drivers.ssd1306 import SSD1306

    oled = SSD1306(I2C(0, sda=Pin(15), scl=Pin(16), freq=400_000))
    oled.text("Hi", 8, 16)
    oled.rect(0, 40, 128, 10, 1)
    panel = hub.sensors.oled
    assert not any("#" in row for row in panel.rows())  # nothing before show()
    oled.show()
    rows = panel.rows()
    for row in range(8):
        assert rows[16 + row][8:24] == glyph_rows("H")[row] + glyph_rows("i")[row]
    # Only the two cells are inked: nothing spills outside them.
    assert not any("#" in rows[y] for y in range(40) if not 16 <= y < 24)
    assert not any("#" in rows[y][:8] + rows[y][24:] for y in range(16, 24))
    assert rows[40] == "#" * 128 and rows[49] == "#" * 128 and rows[45][0] == rows[45][127] == "#"
    oled.invert(True)
    assert panel.rows()[0] == "#" * 128
    oled.poweroff()
    assert not any("#" in row for row in panel.rows())


def test_every_printable_character_has_its_own_glyph_inside_its_cell():
    glyphs = {char: glyph_rows(char) for char in PRINTABLE}
    assert not any("#" in row for row in glyphs[" "])  # a space draws nothing
    inked = {char: tuple(rows) for char, rows in glyphs.items() if char != " "}
    assert all(any("#" in row for row in rows) for rows in inked.values())
    assert len(set(inked.values())) == len(inked)  # distinct characters look distinct
    # A glyph stays inside its 8x8 cell: a character drawn at (8, 8) on a 24x24 frame inks only
    # that cell, and drawing "ab" equals drawing "a" then "b" one cell to the right.
    for char in PRINTABLE:
        frame = sim_framebuf.FrameBuffer(bytearray(24 * 3), 24, 24, sim_framebuf.MONO_VLSB)
        frame.text(char, 8, 8, 1)
        assert all(
            not frame.pixel(x, y) for x in range(24) for y in range(24) if not (8 <= x < 16 and 8 <= y < 16)
        )
    pair = sim_framebuf.FrameBuffer(bytearray(16), 16, 8, sim_framebuf.MONO_VLSB)
    pair.text("ab", 0, 0)
    assert [
        row[:8] for row in ("".join("#" if pair.pixel(x, y) else "." for x in range(16)) for y in range(8))
    ] == glyphs["a"]
    assert ["".join("#" if pair.pixel(x, y) else "." for x in range(8, 16)) for y in range(8)] == glyphs["b"]


def test_lines_and_ellipses_are_connected_and_symmetric():
    size = 32
    frame = sim_framebuf.FrameBuffer(bytearray(size * size // 8), size, size, sim_framebuf.MONO_VLSB)
    for x1, y1, x2, y2 in ((1, 2, 29, 11), (30, 1, 3, 28), (5, 30, 9, 0), (0, 0, 31, 31)):
        frame.fill(0)
        frame.line(x1, y1, x2, y2, 1)
        on = {(x, y) for x in range(size) for y in range(size) if frame.pixel(x, y)}
        assert (x1, y1) in on and (x2, y2) in on
        assert len(on) == max(abs(x2 - x1), abs(y2 - y1)) + 1  # one pixel per step along the major axis
        assert all(
            any(abs(x - u) <= 1 and abs(y - v) <= 1 and (x, y) != (u, v) for u, v in on) for x, y in on
        )
    frame.fill(0)
    frame.ellipse(15, 15, 11, 6, 1, True)
    on = {(x, y) for x in range(size) for y in range(size) if frame.pixel(x, y)}
    assert (15, 15) in on and (4, 15) in on and (26, 15) in on and (15, 9) in on and (15, 21) in on
    assert all((30 - x, y) in on and (x, 30 - y) in on for x, y in on)
    frame.fill(0)
    frame.ellipse(15, 15, 11, 6, 1, False, 0b0001)  # only the top-right quadrant
    on = {(x, y) for x in range(size) for y in range(size) if frame.pixel(x, y)}
    assert (26, 15) in on and (15, 9) in on and all(x >= 15 and y <= 15 for x, y in on)


def test_framebuf_formats_and_drawing_follow_the_builtin_module():
    fb = sim_framebuf.FrameBuffer(bytearray(16 * 2), 16, 16, sim_framebuf.MONO_HLSB)
    fb.pixel(0, 0, 1)
    fb.pixel(9, 1, 1)
    assert bytes(fb._buffer[:4]) == bytes((0x80, 0x00, 0x00, 0x40))  # MSB first within a byte
    rgb = sim_framebuf.FrameBuffer(bytearray(8 * 8 * 2), 8, 8, sim_framebuf.RGB565)
    rgb.fill_rect(-2, -2, 4, 4, 0xF800)
    assert rgb.pixel(1, 1) == 0xF800 and rgb.pixel(2, 2) == 0
    rgb.line(0, 7, 7, 0, 0x07E0)
    assert all(rgb.pixel(i, 7 - i) == 0x07E0 for i in range(8))
    mono = sim_framebuf.FrameBuffer(bytearray(8), 8, 8, sim_framebuf.MONO_VLSB)
    mono.ellipse(3, 3, 3, 3, 1, True)
    assert mono.pixel(3, 3) == 1 and mono.pixel(0, 3) == 1 and mono.pixel(0, 0) == 0
    mono.scroll(1, 0)
    # Shifted right by one; the vacated column keeps what it had, as in the built-in module.
    assert mono.pixel(7, 3) == 1 and mono.pixel(0, 3) == 1 and mono.pixel(7, 0) == 0
    with pytest.raises(ValueError):
        sim_framebuf.FrameBuffer(bytearray(7), 8, 8, sim_framebuf.MONO_VLSB)
