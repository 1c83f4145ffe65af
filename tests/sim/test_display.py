"""An SSD1306 program runs in the simulator: the shim's framebuf draws as MicroPython's built-in
module does (its 8x8 font included), and the OLED model on I2C0 shows what the program pushed."""

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


def glyph_rows(char):
    """The 8x8 font's rows for `char`, as '#'/'.' strings (the font stores columns, bit 0 on top)."""
    code = ord(char) - 32
    columns = sim_framebuf._FONT_8X8[code * 8 : code * 8 + 8]
    return ["".join("#" if column >> row & 1 else "." for column in columns) for row in range(8)]


def test_text_drawn_on_the_oled_appears_on_the_panel_in_the_builtin_font(hub):
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
    # The built-in font's H, not a stand-in block:
    assert glyph_rows("H") == [".##..##."] * 3 + [".######."] + [".##..##."] * 3 + ["........"]
    assert rows[40] == "#" * 128 and rows[49] == "#" * 128 and rows[45][0] == rows[45][127] == "#"
    oled.invert(True)
    assert panel.rows()[0] == "#" * 128
    oled.poweroff()
    assert not any("#" in row for row in panel.rows())


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
