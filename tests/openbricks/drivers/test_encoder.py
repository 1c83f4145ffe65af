"""Encoder counting: interrupt-decoded quadrature and the PCNT peripheral."""

import machine

from fakes.dc_motor import ShaftEdges
from fakes.expect import raises
from openbricks import pins
from openbricks.drivers.encoder import PCNTEncoder, QuadratureEncoder, make_encoder

# A leading B, one full cycle from rest with both lines pulled up.
_FORWARD = ((0, 1), (0, 0), (1, 0), (1, 1))


def _spin(cycles, a=7, b=8):
    """Drive the A/B lines through `cycles` quadrature cycles (negative: backwards)."""
    order = _FORWARD if cycles >= 0 else tuple(reversed(((1, 1),) + _FORWARD[:3]))
    for _ in range(abs(cycles)):
        for level_a, level_b in order:
            if machine.board.input_level(a, 1) != level_a:
                machine.board.set_input(a, level_a)
            if machine.board.input_level(b, 1) != level_b:
                machine.board.set_input(b, level_b)


def test_interrupt_decoder_counts_four_edges_per_cycle_both_ways():
    pins.reset_claims()
    enc = QuadratureEncoder(7, 8)
    _spin(10)
    assert enc.count() == 40
    _spin(-3)
    assert enc.count() == 28
    assert enc.missed == 0


def test_invert_and_reset():
    pins.reset_claims()
    enc = QuadratureEncoder(7, 8, invert=True)
    _spin(2)
    assert enc.count() == -8
    enc.reset(100)
    _spin(1)
    assert enc.count() == 96


def test_a_skipped_state_is_not_counted_but_is_reported():
    pins.reset_claims()
    enc = QuadratureEncoder(7, 8)
    pin_b = machine.board.pins[8]
    machine.board.inputs[7] = 0
    machine.board.inputs[8] = 0
    pin_b._handler(pin_b)  # both lines flipped before the handler ran
    assert enc.count() == 0
    assert enc.missed == 1


def test_interrupt_decoder_pins_are_claimed_and_released():
    pins.reset_claims()
    enc = QuadratureEncoder(7, 8, name="left encoder")
    with raises(pins.ReservedPinError, "in use as the left encoder A"):
        QuadratureEncoder(7, 12)
    enc.close()
    QuadratureEncoder(7, 12)


def test_pcnt_encoder_counts_x4_with_the_glitch_filter_and_invert():
    pins.reset_claims()
    shaft = ShaftEdges(7)
    enc = PCNTEncoder(7, 8, unit=1, invert=True)
    hw = machine.board.pcnt_units[1]
    assert (hw._phase_a, hw._phase_b, hw._phases, hw._filter_ns) == (7, 8, 4, 12787)
    shaft.move(68028)
    assert hw.value() == 68028 and enc.count() == -68028
    enc.reset(0)
    assert hw.value() == 0 and enc.count() == 0
    enc.reset(500)
    assert enc.count() == 500


def test_each_pcnt_unit_counts_one_encoder():
    pins.reset_claims()
    first = PCNTEncoder(7, 8, unit=0)
    with raises(ValueError, "PCNT unit 0 already counts the encoder on GPIO 7/8"):
        PCNTEncoder(12, 13, unit=0)
    assert pins.owner_of(12) is None
    first.close()
    PCNTEncoder(12, 13, unit=0)


def test_a_unit_left_over_from_a_finished_program_is_free_again():
    pins.reset_claims()
    PCNTEncoder(7, 8, unit=2)
    pins.reset_claims()  # what the launcher does with a finished program's claims
    PCNTEncoder(7, 8, unit=2)


def test_pcnt_filter_range_is_checked():
    pins.reset_claims()
    with raises(ValueError, "0..1023 APB cycles"):
        PCNTEncoder(7, 8, unit=3, filter=5000)


def _without_machine_encoder(build):
    """`build()` on a runtime whose machine module has no Encoder (a port without PCNT)."""
    saved = machine.Encoder
    machine.Encoder = None
    try:
        return build()
    finally:
        machine.Encoder = saved


def _idle_high(*pin_ids):
    """Encoder lines at rest on their pull-ups, as _spin() expects them."""
    for pin_id in pin_ids:
        machine.board.inputs[pin_id] = 1


def test_the_pcnt_peripheral_and_the_interrupt_decoder_count_the_same_way():
    pins.reset_claims()
    _idle_high(7, 8, 12, 13)
    pcnt = PCNTEncoder(7, 8, unit=0)
    irq = QuadratureEncoder(12, 13)
    _spin(5)
    _spin(5, a=12, b=13)
    assert pcnt.count() == irq.count() == 20
    _spin(-2)
    _spin(-2, a=12, b=13)
    assert pcnt.count() == irq.count() == 12


def test_make_encoder_counts_on_the_lowest_free_pcnt_unit():
    pins.reset_claims()
    PCNTEncoder(1, 2, unit=0)
    PCNTEncoder(3, 4, unit=2)
    _idle_high(7, 8)
    enc = make_encoder(7, 8, name="left encoder")
    assert isinstance(enc, PCNTEncoder) and enc.unit == 1
    assert machine.board.pcnt_units[1]._phase_a == 7
    _spin(3)
    assert enc.count() == 12
    assert make_encoder(12, 13).unit == 3


def test_make_encoder_honours_a_given_unit_and_its_clash():
    pins.reset_claims()
    assert make_encoder(7, 8, unit=5).unit == 5
    with raises(ValueError, "PCNT unit 5 already counts the encoder on GPIO 7/8"):
        make_encoder(12, 13, unit=5)


def test_without_machine_encoder_the_pins_are_decoded_in_an_interrupt():
    pins.reset_claims()
    enc = _without_machine_encoder(lambda: make_encoder(7, 8, invert=True, unit=1))
    assert isinstance(enc, QuadratureEncoder)
    assert 1 not in machine.board.pcnt_units
    _spin(2)
    assert enc.count() == -8


def test_when_the_chips_pcnt_units_are_all_taken_the_next_encoder_uses_interrupts():
    pins.reset_claims()
    pins.set_chip("esp32s3")
    try:
        taken = [make_encoder(a, a + 1) for a in (1, 3, 5, 7)]
        assert [enc.unit for enc in taken] == [0, 1, 2, 3]
        assert isinstance(make_encoder(9, 10), QuadratureEncoder)
        taken[2].close()
        assert make_encoder(11, 12).unit == 2
    finally:
        pins.set_chip(None)
