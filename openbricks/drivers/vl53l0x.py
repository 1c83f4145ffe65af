"""ST VL53L0X laser time-of-flight range finder (I2C, default address 0x29, up to ~2 m).

One single-shot measurement, as the manual documents it: write 0x01 to
SYSRANGE_START (0x00), poll RESULT_INTERRUPT_STATUS (0x13) until a sample is
flagged (~33 ms at the default timing budget), read the range big-endian at
RESULT_RANGE_STATUS + 10 (0x1E), then clear the interrupt (0x0B). The chip
reports "no target" as 8190 mm, surfaced as -1 per the DistanceSensor
contract. This is the power-on-default ranging that off-the-shelf MicroPython
drivers use; ST's full calibration sequence is not run.
"""

import time

from micropython import const

from openbricks.distance import DistanceSensor

_DEFAULT_ADDR = const(0x29)

_SYSRANGE_START = const(0x00)
_SYSTEM_INTERRUPT_CLEAR = const(0x0B)
_RESULT_INTERRUPT_STATUS = const(0x13)
_RESULT_RANGE_MM = const(0x14 + 10)
_MODEL_ID = const(0xC0)

_VL53L0X_MODEL = const(0xEE)
_NO_TARGET_MM = const(8190)
_POLL_MS = const(2)
_ENODEV = const(19)
_ETIMEDOUT = const(110)


class VL53L0X(DistanceSensor):
    """Laser range finder; `timeout_ms` bounds one measurement (the chip usually needs 33-50 ms)."""

    def __init__(self, i2c, address=_DEFAULT_ADDR, timeout_ms=200):
        self._i2c = i2c
        self._address = address
        self._timeout_ms = timeout_ms
        self._buf = bytearray(2)
        try:
            model = self._read_u8(_MODEL_ID)
        except OSError as e:
            raise OSError(
                _ENODEV,
                "no VL53L0X answers at I2C address 0x%02X (%s): check SDA/SCL/power and that XSHUT is "
                "not held low" % (address, e),
            ) from None
        if model != _VL53L0X_MODEL:
            raise OSError(
                _ENODEV,
                "the chip at I2C address 0x%02X is not a VL53L0X: its model ID (0xC0) reads 0x%02X, "
                "expected 0xEE; a VL53L1X needs openbricks.drivers.vl53l1x, a TCS34725 also sits at "
                "0x29" % (address, model),
            )

    def _read_u8(self, reg):
        return self._i2c.readfrom_mem(self._address, reg, 1)[0]

    def _write_u8(self, reg, value):
        self._i2c.writeto_mem(self._address, reg, bytes((value,)))

    def distance_mm(self):
        """Distance ahead in millimetres; -1 if nothing is in range."""
        self._write_u8(_SYSRANGE_START, 0x01)
        start = time.ticks_ms()
        # Bits 2:0 carry the interrupt cause; the default configuration flags a new sample in bit 0.
        while not self._read_u8(_RESULT_INTERRUPT_STATUS) & 0x07:
            if time.ticks_diff(time.ticks_ms(), start) >= self._timeout_ms:
                raise OSError(
                    _ETIMEDOUT,
                    "VL53L0X at 0x%02X did not finish a measurement within %d ms; power-cycle it, or "
                    "raise timeout_ms" % (self._address, self._timeout_ms),
                )
            time.sleep_ms(_POLL_MS)
        self._i2c.readfrom_mem_into(self._address, _RESULT_RANGE_MM, self._buf)
        self._write_u8(_SYSTEM_INTERRUPT_CLEAR, 0x01)
        mm = (self._buf[0] << 8) | self._buf[1]
        return -1 if mm >= _NO_TARGET_MM else mm

    def __repr__(self):
        return "VL53L0X(address=0x%02X)" % self._address
