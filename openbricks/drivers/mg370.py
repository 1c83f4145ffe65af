"""MG370 geared DC motor with a GMR quadrature encoder: JGB37Motor with the encoder on PCNT.

The GMR encoder gives 500 pulses per motor turn; x4 edges through a 1:34.014
gearbox is ~68028 counts per output turn. That edge rate is far beyond what
a pin interrupt can service, so the ESP32's pulse-counter peripheral counts
it (one PCNT unit per motor, chosen by the caller). On a runtime without
machine.Encoder the encoder falls back to the pin-interrupt decoder, which
only keeps up at low shaft speeds (its `missed` count says when it did not).
Everything else, bridge and native servo core, is the JGB37-520's.
"""

from openbricks.drivers.encoder import make_encoder
from openbricks.drivers.jgb37_520 import _DEFAULT_KP, JGB37Motor

_DEFAULT_CPR = int(500 * 4 * 34.014)
# Nominal output speed at full duty of the 12 V 1:34 variant, for the feed-forward scale;
# pass no_load_dps= to match your motor and supply.
_DEFAULT_NO_LOAD_DPS = 1000.0


class MG370Motor(JGB37Motor):
    """MG370 DC gear motor with GMR encoder, closed loop; `pcnt_unit` must be unique per motor."""

    def __init__(
        self,
        in1,
        in2,
        pwm,
        encoder_a,
        encoder_b,
        pcnt_unit=0,
        pcnt_filter=1023,
        counts_per_output_rev=_DEFAULT_CPR,
        invert=False,
        encoder_invert=False,
        kp=_DEFAULT_KP,
        no_load_dps=_DEFAULT_NO_LOAD_DPS,
    ):
        self.pcnt_filter = pcnt_filter
        JGB37Motor.__init__(
            self,
            in1,
            in2,
            pwm,
            encoder_a,
            encoder_b,
            counts_per_output_rev,
            invert,
            encoder_invert,
            kp,
            no_load_dps,
            pcnt_unit,
        )

    def _make_encoder(self, pin_a, pin_b, invert):
        return make_encoder(
            pin_a,
            pin_b,
            invert=invert,
            name="MG370 encoder",
            unit=self.pcnt_unit,
            filter=self.pcnt_filter,
            counts_per_rev=self.counts_per_output_rev,
        )
