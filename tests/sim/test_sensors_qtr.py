"""The QTR bar model: the line shows up under the elements it really lies under, dark reads high,
and every pin of one instant comes from one look at the mat."""

import pytest

from openbricks_sim.sensors.mat import GroundProbe
from openbricks_sim.sensors.qtr import POSITIONS_MM, QTRBarModel
from openbricks_sim.sensors.registers import physics_clock_us
from openbricks_sim.worlds import WORLDS, line_track

from .placed import place, step_ms

START_X, START_Y, _ = WORLDS["line_track"].start_mm_deg  # the start line runs along y = START_Y, heading 0


def bar(alias, x_mm, y_mm, heading_deg=0.0, **kw):
    model, data = place(alias, x_mm, y_mm, heading_deg)
    return QTRBarModel(GroundProbe(model, data), physics_clock_us(data), **kw), model, data


def dark_positions(raw, threshold=2000):
    return [x for x, r in zip(POSITIONS_MM, raw, strict=True) if r > threshold]


def test_line_centred_under_the_bar_darkens_the_middle_elements_only():
    qtr, _, _ = bar("line_track", START_X, START_Y)
    raw = qtr.raw12()
    assert dark_positions(raw) == [-4.0, 4.0]  # the 20 mm line covers -10..+10 mm
    assert all(r > 3400 for r in raw[4:6])
    assert all(r < 500 for r in raw[:3] + raw[7:])


def test_line_to_the_robots_left_shows_on_the_left_elements():
    # The robot 16 mm to the right of the line (its y is 16 mm lower): the line lies at -16 mm.
    qtr, _, _ = bar("line_track", START_X, START_Y - 16.0)
    assert dark_positions(qtr.raw12()) == [-20.0, -16.0, -12.0]


def test_line_to_the_robots_right_shows_on_the_right_elements():
    qtr, _, _ = bar("line_track", START_X, START_Y + 16.0)
    assert dark_positions(qtr.raw12()) == [12.0, 16.0, 20.0]


def test_heading_turns_the_bar_over_the_mat():
    # Facing down the mat (heading 90) on the line's x: the start line now crosses the bar.
    qtr, _, _ = bar("line_track", -600.0, START_Y + 70.0, 90.0)
    raw = qtr.raw12()
    assert len(dark_positions(raw)) == 10


def test_finish_bar_darkens_the_whole_window():
    path, _ = line_track.route()
    # Facing the bar along the home straight (toward -y), the QTR 70 mm ahead over it.
    qtr, _, _ = bar("line_track", path.x_mm, path.y_mm - 20.0 + 70.0, 90.0)
    assert len(dark_positions(qtr.raw12())) == 10


def test_an_element_half_over_the_edge_reads_in_between():
    # Line edge at y = START_Y + 10; put element -12 mm (12 mm left) right on it.
    qtr, _, _ = bar("line_track", START_X, START_Y + 10.0 - 12.0)
    raw = qtr.raw12()
    assert 1200 < raw[POSITIONS_MM.index(-12.0)] < 2700


def test_one_coherent_sample_per_instant_and_a_fresh_one_later():
    qtr, model, data = bar("line_track", START_X, START_Y)
    pins = [qtr.channel(pin) for pin in qtr.pins]
    first = [p.read() for p in pins]
    assert [p.read() for p in pins] == first  # same instant: the same sample, noise included
    step_ms(model, data, 1)
    later = [p.read() for p in pins]
    assert later != first  # fresh noise
    assert dark_positions(later) == dark_positions(first)


def test_read_u16_spans_the_sixteen_bit_range():
    qtr, _, _ = bar("line_track", START_X, START_Y)
    dark = qtr.channel(5)
    assert dark.read_u16() >> 4 == dark.read()


def test_same_seed_same_noise():
    a, _, _ = bar("line_track", START_X, START_Y, seed=3)
    b, _, _ = bar("line_track", START_X, START_Y, seed=3)
    c, _, _ = bar("line_track", START_X, START_Y, seed=4)
    assert a.raw12() == b.raw12()
    assert a.raw12() != c.raw12()


def test_lifted_off_the_mat_every_element_reads_dark():
    qtr, model, data = bar("line_track", -500.0, 300.0)
    assert max(qtr.raw12()) < 500
    data.qpos[2] += 0.3  # 300 mm up: nothing within range reflects the emitters
    step_ms(model, data, 1)
    assert min(qtr.raw12()) > 3400


def test_wiring_mistakes_are_named():
    qtr, _, _ = bar("line_track", START_X, START_Y)
    with pytest.raises(ValueError, match="GPIO 11"):
        qtr.channel(11)
