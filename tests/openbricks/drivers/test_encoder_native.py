"""PCNTEncoder on the firmware's native counter: what the ESP32 image does with an encoder.

The image's `_openbricks_native.PCNTEncoder` is the encoder core (firmware/native/encoder.c) over a
PCNT unit that the hard tick reads every millisecond. No PCNT here, so `HubCounter` stands in for the
peripheral only: the real core, fed what a unit's counter reads (it returns to 0 at +-32767).
"""

import _openbricks_native
import machine

from fakes.expect import approx, raises
from openbricks import pins
from openbricks.drivers import encoder
from openbricks.drivers.mg370 import MG370Motor

NEEDS_NATIVE = True
_LIMIT = 32767


class HubCounter:
    """The firmware's PCNTEncoder, with a modelled PCNT unit where the image has the peripheral."""

    HARDWARE = True
    built = []

    def __init__(self, counts_per_rev, invert=False, pin_a=None, pin_b=None, unit=0, filter=1023):
        self.core = _openbricks_native.PCNTEncoder(counts_per_rev, invert=invert)
        self.wiring = (pin_a, pin_b, unit, filter)
        self.raw = 0
        self.closed = False
        self.core.sample(self.raw)
        HubCounter.built.append(self)

    def turn(self, counts, per_tick=500):
        """The shaft moves `counts` edges; the hard tick reads the unit every `per_tick` of them."""
        step = per_tick if counts >= 0 else -per_tick
        while counts != 0:
            move = step if abs(counts) > per_tick else counts
            counts -= move
            self.raw += move
            while self.raw >= _LIMIT:
                self.raw -= _LIMIT
            while self.raw <= -_LIMIT:
                self.raw += _LIMIT
            self.core.sample(self.raw)

    def count(self):
        return self.core.count()

    def reset(self, count=0):
        self.core.reset(count)

    def close(self):
        self.closed = True
        self.core.close()


def _on_the_hub(test):
    saved = encoder._hub_counter
    encoder._hub_counter = lambda: HubCounter
    HubCounter.built = []
    pins.reset_claims()
    try:
        test()
    finally:
        encoder._hub_counter = saved


def test_the_firmware_counts_on_its_native_counter_not_machine_encoder():
    def test():
        before = dict(machine.board.pcnt_units)
        enc = encoder.PCNTEncoder(7, 8, unit=1, filter=200, invert=True, counts_per_rev=68028)
        (hub,) = HubCounter.built
        assert hub.wiring == (7, 8, 1, 200)
        assert machine.board.pcnt_units == before
        hub.turn(3 * 68028)  # six wraps of the 16-bit counter
        assert enc.count() == -3 * 68028
        enc.reset(500)
        hub.turn(-100)
        assert enc.count() == 600
        enc.close()
        assert hub.closed and pins.owner_of(7) is None

    _on_the_hub(test)


def test_make_encoder_picks_the_native_counter_on_the_firmware():
    def test():
        enc = encoder.make_encoder(7, 8, name="left encoder", counts_per_rev=1320.4)
        assert isinstance(enc, encoder.PCNTEncoder) and enc.unit == 0
        assert HubCounter.built[0].core.max_step() == 16383
        with raises(ValueError, "PCNT unit 0 already counts the encoder on GPIO 7/8"):
            encoder.PCNTEncoder(12, 13, unit=0)

    _on_the_hub(test)


def test_an_mg370_reads_its_angle_through_the_native_counter():
    def test():
        motor = MG370Motor(in1=1, in2=2, pwm=17, encoder_a=7, encoder_b=8, pcnt_unit=0)
        (hub,) = HubCounter.built
        hub.turn(68028 // 2)
        assert approx(motor.angle(), 180.0, 0.01)
        motor.reset_angle(0)
        hub.turn(-68028)
        assert approx(motor.angle(), -360.0, 0.01)
        motor.close()
        assert hub.closed

    _on_the_hub(test)


def test_a_finished_programs_counter_gives_its_unit_back_when_the_next_one_counts():
    def test():
        encoder.PCNTEncoder(7, 8, unit=0)
        (first,) = HubCounter.built
        pins.reset_claims()  # what the launcher does with a finished program's claims
        encoder.PCNTEncoder(12, 13, unit=1)
        assert first.closed  # its PCNT unit and hard-tick slot are free again
        assert not HubCounter.built[1].closed

    _on_the_hub(test)
