"""L298N dual H-bridge: one brushed DC motor per channel, open loop.

    IN1 IN2  bridge
     0   0   coast (outputs off)
     1   0   forward
     0   1   reverse
     1   1   brake (both low-side switches on: the winding is shorted)

Speed is the PWM duty on EN. With no encoder only dc / brake / coast exist;
the closed-loop half of the Motor contract raises (JGB37Motor adds an
encoder to the same bridge channel).

On the firmware the pins belong to the native H-bridge core
(`_openbricks_native.HBridge`: GPIO and an LEDC channel, driven from C), so a
controller over the bridge can write it from the hard tick with no Python
call. Elsewhere (the simulator) they are machine.Pin and machine.PWM.
"""

from micropython import const

from openbricks import _native, estop
from openbricks.drivers import claim_pins, release_pins
from openbricks.interfaces import Motor

# The L298N's bipolar switches are slow; a few kHz keeps switching losses and duty distortion small.
_PWM_FREQ_HZ = const(1000)


class L298NMotor(Motor):
    """Open-loop brushed DC motor on one H-bridge channel."""

    CHIP = "L298N"

    def __init__(self, in1, in2, pwm, invert=False, pwm_freq=_PWM_FREQ_HZ):
        self.invert = bool(invert)
        self._pins = (in1, in2, pwm)
        claim_pins(
            self,
            (
                (in1, self.CHIP + " IN1", True),
                (in2, self.CHIP + " IN2", True),
                (pwm, self.CHIP + " PWM/EN", True),
            ),
        )
        try:
            native = _hub_bridge()
            if native is not None:
                # The core applies `invert` itself and owns the pins from here on.
                self._native = native(in1, in2, pwm, invert=self.invert, freq_hz=pwm_freq)
            else:
                from machine import PWM, Pin

                self._native = None
                self._in1 = Pin(in1, Pin.OUT, value=0)
                self._in2 = Pin(in2, Pin.OUT, value=0)
                self._pwm = PWM(Pin(pwm, Pin.OUT), freq=pwm_freq, duty_u16=0)
        except Exception:
            release_pins(self, self._pins)
            raise
        self._duty = 0
        estop.on_engage(self.coast)  # the stop button frees the bridge at once

    def dc(self, duty):
        """Fixed duty -100..100 (sign = direction, after invert). 0 releases the motor like coast().

        Refused (EStopError) while the e-stop is engaged.
        """
        estop.check("%s dc()" % self.CHIP)
        self._drive(duty)

    def _drive(self, duty):
        """dc() without the e-stop check: for a controller's own output path (its tick must not raise)."""
        duty = max(-100, min(100, duty))
        if duty == 0:
            self.coast()
            return
        if self._native is not None:
            self._native.drive(duty)
            self._duty = -duty if self.invert else duty
            return
        if self.invert:
            duty = -duty
        self._in1.value(1 if duty > 0 else 0)
        self._in2.value(0 if duty > 0 else 1)
        self._pwm.duty_u16(int(abs(duty) * 65535 / 100))
        self._duty = duty

    def brake(self):
        """Short the winding: the motor's own back-EMF stops it quickly."""
        self._duty = 0
        if self._native is not None:
            self._native.brake()
            return
        self._in1.value(1)
        self._in2.value(1)
        self._pwm.duty_u16(65535)

    def coast(self):
        """Switch the bridge off: the motor spins down freely."""
        self._duty = 0
        if self._native is not None:
            self._native.coast()
            return
        self._pwm.duty_u16(0)
        self._in1.value(0)
        self._in2.value(0)

    def close(self):
        """Release the bridge and hand its pins back."""
        self.coast()
        estop.remove(self.coast)
        if self._native is not None:
            self._native.close()
        else:
            self._pwm.deinit()
        release_pins(self, self._pins)

    def native_bridge(self):
        """The firmware's H-bridge core driving these pins, or None where Python drives them."""
        return self._native


def _hub_bridge():
    """The firmware's native HBridge when this build drives pins with it (the ESP32 image), else None."""
    bridge = _native.get("HBridge")
    return bridge if bridge is not None and bridge.HARDWARE else None
