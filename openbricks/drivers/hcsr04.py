"""HC-SR04 ultrasonic range finder on two GPIOs.

A 10 us pulse on TRIG fires a burst; ECHO then stays high for the sound's
round trip, timed by `machine.time_pulse_us`. distance = pulse_us x 0.343
mm/us / 2. Plain Python: a range sensor has no closed loop that needs the
1 kHz path.
"""

import time

from machine import Pin, time_pulse_us
from micropython import const

from openbricks import pins
from openbricks.distance import DistanceSensor

_DEFAULT_TIMEOUT_US = const(30_000)  # ~5 m round trip, beyond the sensor's 4 m rating
_SOUND_MM_PER_US = 0.343  # dry air at about 20 degrees C
# Echoes of one ping ring for tens of ms; the datasheet asks for >= 60 ms between triggers so a
# late echo of the previous ping is not timed as this one.
_CYCLE_MS = const(60)


class HCSR04(DistanceSensor):
    """Ultrasonic range finder on GPIOs `trig` and `echo`; `timeout_us` bounds the wait for an echo."""

    def __init__(self, trig, echo, timeout_us=_DEFAULT_TIMEOUT_US):
        pins.claim(trig, "HC-SR04 TRIG output", owner=self)
        pins.claim(echo, "HC-SR04 ECHO input", owner=self, output=False)
        self._trig = Pin(trig, Pin.OUT, value=0)
        self._echo = Pin(echo, Pin.IN)
        self._timeout_us = timeout_us
        self._trig_pin = trig
        self._echo_pin = echo
        self._last_ping_ms = None

    def distance_mm(self):
        """Distance to the nearest reflector ahead in millimetres, or -1 if no echo came back in time."""
        if self._last_ping_ms is not None:
            wait_ms = _CYCLE_MS - time.ticks_diff(time.ticks_ms(), self._last_ping_ms)
            if wait_ms > 0:
                time.sleep_ms(wait_ms)
        self._trig.value(0)
        time.sleep_us(2)
        self._trig.value(1)
        time.sleep_us(10)
        self._trig.value(0)
        self._last_ping_ms = time.ticks_ms()
        pulse_us = time_pulse_us(self._echo, 1, self._timeout_us)
        if pulse_us < 0:  # -1: no echo started in time; -2: the echo never ended
            return -1
        return int(pulse_us * _SOUND_MM_PER_US / 2 + 0.5)

    def __repr__(self):
        return "HCSR04(trig=%d, echo=%d)" % (self._trig_pin, self._echo_pin)
