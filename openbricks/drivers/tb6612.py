"""TB6612FNG dual MOSFET H-bridge: the L298N's control scheme (IN1/IN2 + PWM) on better silicon.

MOSFETs drop ~0.3 V instead of ~1.8 V, take 3.3 V logic directly and switch
fast enough to PWM above hearing. STBY must be high for either channel to
run; breakout boards usually pull it up, so the driver does not model it.
"""

from micropython import const

from openbricks.drivers.l298n import L298NMotor

# Above the audible range; the TB6612 switches cleanly up to 100 kHz.
_PWM_FREQ_HZ = const(20000)


class TB6612Motor(L298NMotor):
    """Open-loop brushed DC motor on one TB6612 channel; same behaviour as L298NMotor."""

    CHIP = "TB6612"

    def __init__(self, in1, in2, pwm, invert=False, pwm_freq=_PWM_FREQ_HZ):
        L298NMotor.__init__(self, in1, in2, pwm, invert, pwm_freq)
