"""MG370 open-loop side: the GMR encoder counted by a PCNT unit, one unit per motor."""

import machine

from fakes.dc_motor import ShaftEdges
from fakes.expect import approx, raises
from openbricks import pins
from openbricks.drivers.mg370 import MG370Motor


def _fresh():
    pins.reset_claims()
    try:
        import _openbricks_native

        _openbricks_native.motor_process.reset()
    except ImportError:
        pass


def test_angle_comes_from_the_pcnt_unit_at_68028_counts_per_turn():
    _fresh()
    shaft = ShaftEdges(7)
    m = MG370Motor(in1=1, in2=2, pwm=17, encoder_a=7, encoder_b=8, pcnt_unit=1)
    hw = machine.board.pcnt_units[1]
    assert (hw._phase_a, hw._phase_b, hw._phases) == (7, 8, 4)
    shaft.move(68028 // 4)
    assert approx(m.angle(), 90, 0.01)
    m.reset_angle(0)
    shaft.move(-68028)
    assert approx(m.angle(), -360, 0.01)


def test_invert_flips_the_pcnt_reading_with_the_bridge():
    _fresh()
    shaft = ShaftEdges(7)
    m = MG370Motor(in1=1, in2=2, pwm=17, encoder_a=7, encoder_b=8, invert=True)
    m.dc(25)
    assert (machine.board.pins[1].value(), machine.board.pins[2].value()) == (0, 1)
    shaft.move(-68028 // 2)
    assert approx(m.angle(), 180, 0.01)


def test_two_motors_need_two_pcnt_units():
    _fresh()
    MG370Motor(in1=1, in2=2, pwm=17, encoder_a=7, encoder_b=8, pcnt_unit=0)
    with raises(ValueError, "PCNT unit 0 already counts the encoder on GPIO 7/8"):
        MG370Motor(in1=9, in2=10, pwm=11, encoder_a=12, encoder_b=13, pcnt_unit=0)
    assert pins.owner_of(9) is None  # the refused motor kept none of its pins
    MG370Motor(in1=9, in2=10, pwm=11, encoder_a=12, encoder_b=13, pcnt_unit=1)


def test_pcnt_filter_reaches_the_peripheral():
    _fresh()
    MG370Motor(in1=1, in2=2, pwm=17, encoder_a=7, encoder_b=8, pcnt_unit=2, pcnt_filter=400)
    assert machine.board.pcnt_units[2]._filter_ns == 5000


def test_without_machine_encoder_it_falls_back_to_the_interrupt_decoder():
    from fakes.dc_motor import QuadratureLines

    _fresh()
    lines = QuadratureLines(7, 8)
    saved = machine.Encoder
    machine.Encoder = None
    try:
        m = MG370Motor(in1=1, in2=2, pwm=17, encoder_a=7, encoder_b=8)
    finally:
        machine.Encoder = saved
    assert not machine.board.pcnt_units
    lines.move(1000)
    assert approx(m.angle(), 1000 * 360 / 68028, 1e-6)
    assert m._encoder.missed == 0
