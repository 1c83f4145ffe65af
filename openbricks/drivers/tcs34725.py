"""AMS TCS34725 RGB + clear light-to-digital sensor (I2C, fixed address 0x29).

Register access goes through the command byte (datasheet section 3):
bit 7 CMD = 1, bits 6:5 TYPE (01 = auto-increment, so one 8-byte read
returns clear, red, green and blue from the same integration), bits 4:0
the register. Two sensors on one robot need a TCA9548A channel each.
"""

import struct
import time

from micropython import const

from openbricks.interfaces import ColorSensor

_ADDR = const(0x29)

_CMD = const(0x80)
_AUTO_INCREMENT = const(0x20)

_ENABLE = const(0x00)
_ATIME = const(0x01)
_CONTROL = const(0x0F)
_ID = const(0x12)
_STATUS = const(0x13)
_CDATAL = const(0x14)

_ENABLE_PON = const(0x01)
_ENABLE_AEN = const(0x02)
_STATUS_AVALID = const(0x01)

# 0x44 = TCS34721/TCS34725, 0x4D = TCS34723/TCS34727: one register map, different I2C levels.
_KNOWN_IDS = (0x44, 0x4D)
_GAINS = (1, 4, 16, 60)  # CONTROL.AGAIN 0..3

_CYCLE_MS = 2.4  # one ADC integration cycle
_COUNTS_PER_CYCLE = const(1024)
_ENODEV = const(19)
_ETIMEDOUT = const(110)


class TCS34725(ColorSensor):
    """RGB + clear colour sensor at 0x29.

    `integration_ms` is rounded to whole 2.4 ms ADC cycles (2.4 .. 614.4 ms);
    longer integrates more light (better in dim light, slower to update).
    `gain` is the analog gain: 1, 4, 16 or 60.
    """

    def __init__(self, i2c, address=_ADDR, integration_ms=2.4, gain=16):
        cycles = int(integration_ms / _CYCLE_MS + 0.5)
        if not 1 <= cycles <= 256:
            raise ValueError(
                "TCS34725 integration_ms must be 2.4 .. 614.4 (whole 2.4 ms cycles), got %r"
                % (integration_ms,)
            )
        if gain not in _GAINS:
            raise ValueError("TCS34725 gain must be one of 1, 4, 16, 60, got %r" % (gain,))
        self._i2c = i2c
        self._address = address
        self._cycles = cycles
        self._gain = gain
        self._max_count = min(65535, _COUNTS_PER_CYCLE * cycles)
        self._buf = bytearray(8)
        self._check_identity()
        self._write(_ATIME, 256 - cycles)
        self._write(_CONTROL, _GAINS.index(gain))
        # PON first, then AEN once the oscillator has warmed up (datasheet: 2.4 ms after PON).
        self._write(_ENABLE, _ENABLE_PON)
        time.sleep_ms(3)
        self._write(_ENABLE, _ENABLE_PON | _ENABLE_AEN)
        self._wait_first_integration()

    def _write(self, reg, value):
        self._i2c.writeto_mem(self._address, _CMD | reg, bytes((value,)))

    def _read_u8(self, reg):
        return self._i2c.readfrom_mem(self._address, _CMD | reg, 1)[0]

    def _check_identity(self):
        try:
            chip_id = self._read_u8(_ID)
        except OSError as e:
            raise OSError(
                _ENODEV,
                "no TCS34725 answers at I2C address 0x%02X (%s): check SDA/SCL/power, or the mux "
                "channel it is wired to" % (self._address, e),
            ) from None
        if chip_id not in _KNOWN_IDS:
            raise OSError(
                _ENODEV,
                "the chip at I2C address 0x%02X is not a TCS34725: its ID register (0x12) reads 0x%02X, "
                "expected 0x44 or 0x4D; a VL53L0X/VL53L1X also sits at 0x29, give each its own mux "
                "channel" % (self._address, chip_id),
            )

    def _wait_first_integration(self):
        # Until the first cycle completes the data registers read 0, which would look like black.
        budget_ms = int(_CYCLE_MS * self._cycles) + 10
        start = time.ticks_ms()
        while not self._read_u8(_STATUS) & _STATUS_AVALID:
            if time.ticks_diff(time.ticks_ms(), start) > budget_ms:
                raise OSError(
                    _ETIMEDOUT,
                    "TCS34725 at 0x%02X never completed an integration (STATUS.AVALID stayed 0 for %d ms)"
                    % (self._address, budget_ms),
                )
            time.sleep_ms(1)

    def raw(self):
        """The latest (clear, red, green, blue) 16-bit counts, all from one integration."""
        self._i2c.readfrom_mem_into(self._address, _CMD | _AUTO_INCREMENT | _CDATAL, self._buf)
        return struct.unpack("<4H", self._buf)

    def rgb(self):
        """(r, g, b) 0..255 relative to the clear channel, so brightness cancels out.

        The clear photodiode sees roughly what the red, green and blue ones
        share between them, so for white each colour is about a third of
        clear: scaling channel / clear by 3 puts white near (255, 255, 255)
        at any light level within range. A saturated colour would push its
        strongest channel past 255; the three are then scaled down together
        rather than clipped, so two strong channels keep their order (green
        vs cyan, yellow vs orange). Clear = 0 (darkness) gives black.
        """
        c, r, g, b = self.raw()
        if c == 0:
            return (0, 0, 0)
        # channel * 765 / clear, with the divisor raised when the strongest channel would overflow.
        divisor = max(c, 3 * max(r, g, b))
        return (r * 765 // divisor, g * 765 // divisor, b * 765 // divisor)

    def ambient(self):
        """Clear-channel brightness 0..100; 100 = the ADC is saturated for this integration time."""
        c = self.raw()[0]
        return min(100, c * 100 // self._max_count)

    def __repr__(self):
        return "TCS34725(address=0x%02X, integration_ms=%.1f, gain=%d)" % (
            self._address,
            self._cycles * _CYCLE_MS,
            self._gain,
        )
