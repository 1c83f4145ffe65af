"""Feetech ST-3032 (STS3032): the 12 V sibling of the ST-3215 on the same SCS protocol.

Same 4096-count magnetic encoder, modes and register map, so the classes are
the ST-3215 ones under the hardware's own name, with the datasheet figures
that differ: 148 RPM (888 deg/s) no-load speed and 10 kg*cm (980 mNm) stall
torque. They share the ST-3215 bus registry, so both models can sit on one
daisy chain (on a 12 V rail: the ST-3032 browns out below about 9 V).
"""

from openbricks.drivers.st3215 import _DEFAULT_STEPS_PER_DPS, ST3215, ST3215Motor

ST3032_NO_LOAD_DPS = 888.0
_STALL_TORQUE_MNM = 980.0


class ST3032(ST3215):
    """One ST-3032 in position mode; see ST3215."""

    #: Datasheet stall torque of the ST-3032 in mNm (10 kg.cm).
    STALL_TORQUE_MNM = _STALL_TORQUE_MNM


class ST3032Motor(ST3215Motor):
    """One ST-3032 as a wheel; see ST3215Motor. max_dps defaults to the datasheet no-load speed."""

    #: Datasheet stall torque of the ST-3032 in mNm (10 kg.cm): the scale of load().
    STALL_TORQUE_MNM = _STALL_TORQUE_MNM

    def __init__(
        self,
        servo_id,
        uart_id=1,
        tx=14,
        rx=41,
        baud=1_000_000,
        dir_pin=None,
        invert=False,
        steps_per_dps=_DEFAULT_STEPS_PER_DPS,
        max_dps=ST3032_NO_LOAD_DPS,
        accel_dps2=1500.0,
        raise_on_stall=False,
        stall_idle_ms=1000,
    ):
        ST3215Motor.__init__(
            self,
            servo_id,
            uart_id,
            tx,
            rx,
            baud,
            dir_pin,
            invert,
            steps_per_dps,
            max_dps,
            accel_dps2,
            raise_on_stall,
            stall_idle_ms,
        )
