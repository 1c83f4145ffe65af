"""SSD1306 against a model of the controller: what a person looking at the panel would see."""

from machine import I2C, board

from fakes.expect import raises
from fakes.i2c_chips import SSD1306Chip
from openbricks.drivers.ssd1306 import SSD1306


def _display(height=64, addr=0x3C):
    chip = SSD1306Chip(height=height)
    board.attach_i2c(0, addr, chip)
    return SSD1306(I2C(0), addr=addr, height=height), chip


def test_construction_switches_the_panel_on_blank_and_upright():
    oled, chip = _display()
    assert chip.display_on and chip.charge_pump
    assert chip.seg_remap and chip.com_reversed
    assert chip.lit_pixels() == []


def test_nothing_appears_until_show():
    oled, chip = _display()
    oled.pixel(0, 0, 1)
    oled.pixel(127, 63, 1)
    assert chip.lit_pixels() == []
    oled.show()
    assert chip.lit_pixels() == [(0, 0), (127, 63)]
    assert oled.pixel(127, 63) == 1 and oled.pixel(5, 5) == 0


def test_text_lands_in_its_8x8_cells_and_dark_text_cuts_into_a_lit_screen():
    oled, chip = _display()
    oled.text("Hi", 8, 16)
    oled.show()
    lit = chip.lit_pixels()
    assert lit
    assert all(8 <= x < 24 and 16 <= y < 24 for x, y in lit)
    assert any(x < 16 for x, _ in lit) and any(x >= 16 for x, _ in lit)
    oled.fill(1)
    oled.text("Hi", 8, 16, 0)
    oled.show()
    dark = [(x, y) for y in range(64) for x in range(128) if not chip.lit(x, y)]
    assert dark and all(8 <= x < 24 and 16 <= y < 24 for x, y in dark)


def test_clear_blanks_the_panel_immediately():
    oled, chip = _display()
    oled.fill(1)
    oled.show()
    assert len(chip.lit_pixels()) == 128 * 64
    oled.clear()
    assert chip.lit_pixels() == []


def test_other_drawing_calls_reach_the_frame_buffer():
    oled, chip = _display()
    oled.rect(0, 0, 10, 5, 1)
    oled.hline(20, 30, 4, 1)
    oled.show()
    lit = set(chip.lit_pixels())
    assert (0, 0) in lit and (9, 4) in lit and (5, 2) not in lit
    assert {(20, 30), (23, 30)} <= lit
    with raises(AttributeError):
        oled.no_such_method()


def test_a_refresh_is_one_data_transfer_of_the_whole_frame():
    oled, chip = _display()
    before = chip.data_bytes
    oled.show()
    assert chip.data_bytes - before == 128 * 64 // 8


def test_a_128x32_panel_is_driven_with_its_own_multiplex_and_com_pins():
    oled, chip = _display(height=32)
    assert chip.multiplex == 31
    assert (0xDA, (0x02,)) in chip.commands
    oled.pixel(127, 31, 1)
    oled.show()
    assert chip.lit_pixels() == [(127, 31)]


def test_contrast_invert_and_power():
    oled, chip = _display()
    oled.contrast(40)
    assert chip.contrast == 40
    oled.invert(True)
    assert len(chip.lit_pixels()) == 128 * 64
    oled.invert(False)
    oled.poweroff()
    assert not chip.display_on
    oled.poweron()
    assert chip.display_on
    with raises(ValueError, "0..255"):
        oled.contrast(300)


def test_missing_display_names_the_address_and_the_alternative():
    with raises(OSError, "addr=0x3D"):
        SSD1306(I2C(0))


def test_unsupported_panel_size_is_refused():
    board.attach_i2c(0, 0x3C, SSD1306Chip())
    with raises(ValueError, "128x64, 128x32"):
        SSD1306(I2C(0), width=96, height=16)
