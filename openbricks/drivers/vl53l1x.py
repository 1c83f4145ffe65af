"""ST VL53L1X laser time-of-flight range finder (I2C, default address 0x29, up to ~4 m).

Registers have 16-bit addresses, sent high byte first. The model ID at 0x010F
reads 0xEACC (0xEBAA on the pin-compatible VL53L4CD, accepted too). One
single-shot measurement: clear a pending interrupt (0x0086), start with 0x40
in SYSTEM_MODE_START (0x0087), poll GPIO_TIO_HV_STATUS (0x0031) until bit 0
drops (the interrupt is active-low), read the range big-endian at 0x0096,
clear the interrupt again. Like the L0X driver this runs the chip's
power-on-default ranging, without ST's calibration pass.
"""

import time

from micropython import const

from openbricks.distance import DistanceSensor

_DEFAULT_ADDR = const(0x29)

_SYSTEM_INTERRUPT_CLEAR = const(0x0086)
_SYSTEM_MODE_START = const(0x0087)
_GPIO_TIO_HV_STATUS = const(0x0031)
_RESULT_RANGE_STATUS = const(0x0089)
_RESULT_RANGE_MM = const(0x0096)
_FIRMWARE_SYSTEM_STATUS = const(0x00E5)
_MODEL_ID = const(0x010F)

_MODELS = {0xEACC: "VL53L1X", 0xEBAA: "VL53L4CD"}
_RANGE_VALID = const(9)  # RESULT_RANGE_STATUS low bits for "range valid"
_BOOT_MS = const(100)
_POLL_MS = const(2)
_ENODEV = const(19)
_ETIMEDOUT = const(110)


class VL53L1X(DistanceSensor):
    """Long-range laser range finder; `timeout_ms` bounds one measurement (typically ~50 ms)."""

    def __init__(self, i2c, address=_DEFAULT_ADDR, timeout_ms=200):
        self._i2c = i2c
        self._address = address
        self._timeout_ms = timeout_ms
        self._buf = bytearray(2)
        try:
            model = self._read_u16_16(_MODEL_ID)
        except OSError as e:
            raise OSError(
                _ENODEV,
                "no VL53L1X answers at I2C address 0x%02X (%s): check SDA/SCL/power and that XSHUT is "
                "not held low" % (address, e),
            ) from None
        self.model = _MODELS.get(model)
        if self.model is None:
            raise OSError(
                _ENODEV,
                "the chip at I2C address 0x%02X is not a VL53L1X: its model ID (0x010F) reads 0x%04X, "
                "expected 0xEACC (or 0xEBAA for a VL53L4CD); a VL53L0X needs openbricks.drivers.vl53l0x"
                % (address, model),
            )
        self._wait_boot()

    def _read_u8_16(self, reg):
        return self._i2c.readfrom_mem(self._address, reg, 1, addrsize=16)[0]

    def _read_u16_16(self, reg):
        self._i2c.readfrom_mem_into(self._address, reg, self._buf, addrsize=16)
        return (self._buf[0] << 8) | self._buf[1]

    def _write_u8_16(self, reg, value):
        self._i2c.writeto_mem(self._address, reg, bytes((value,)), addrsize=16)

    def _wait_boot(self):
        # Right after power-up (or XSHUT release) the firmware is still booting and ignores commands.
        start = time.ticks_ms()
        while not self._read_u8_16(_FIRMWARE_SYSTEM_STATUS) & 0x01:
            if time.ticks_diff(time.ticks_ms(), start) >= _BOOT_MS:
                raise OSError(
                    _ETIMEDOUT,
                    "VL53L1X at 0x%02X did not finish booting within %d ms (FIRMWARE_SYSTEM_STATUS stays 0)"
                    % (self._address, _BOOT_MS),
                )
            time.sleep_ms(1)

    def distance_mm(self):
        """Distance ahead in millimetres; -1 if nothing is in range."""
        # Clearing first means a ranging that completed after an earlier timeout cannot be read
        # back as this one's result.
        self._write_u8_16(_SYSTEM_INTERRUPT_CLEAR, 0x01)
        self._write_u8_16(_SYSTEM_MODE_START, 0x40)
        start = time.ticks_ms()
        while self._read_u8_16(_GPIO_TIO_HV_STATUS) & 0x01:
            if time.ticks_diff(time.ticks_ms(), start) >= self._timeout_ms:
                raise OSError(
                    _ETIMEDOUT,
                    "VL53L1X at 0x%02X did not finish a measurement within %d ms; power-cycle it, or "
                    "raise timeout_ms" % (self._address, self._timeout_ms),
                )
            time.sleep_ms(_POLL_MS)
        status = self._read_u8_16(_RESULT_RANGE_STATUS) & 0x1F
        mm = self._read_u16_16(_RESULT_RANGE_MM)
        self._write_u8_16(_SYSTEM_INTERRUPT_CLEAR, 0x01)
        return mm if status == _RANGE_VALID else -1

    def __repr__(self):
        return "%s(address=0x%02X)" % (self.model, self._address)
