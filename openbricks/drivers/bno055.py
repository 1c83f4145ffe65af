"""Bosch BNO055 9-axis IMU on I2C, in its IMU fusion mode (accelerometer + gyro).

The magnetometer is deliberately left out: motor magnets and steel in floors
bend the local field, and a drive base only needs relative heading. The chip
fuses on board; this driver configures it and reads the fused Euler angles.
Heading is zeroed where the robot points at construction and wrapped to
[-180, 180), clockwise-positive (the chip's own yaw turns clockwise-positive,
compass-style).

Register map (datasheet BST-BNO055-DS000, page 0): CHIP_ID 0x00 = 0xA0,
ACC_DATA 0x08 (1 m/s^2 = 100 LSB), GYR_DATA 0x14 (1 dps = 16 LSB), EUL_DATA
0x1A heading/roll/pitch (1 deg = 16 LSB), UNIT_SEL 0x3B, OPR_MODE 0x3D,
PWR_MODE 0x3E, all little-endian int16.
"""

import struct
import time

from micropython import const

from openbricks.interfaces import IMU, HeadingFrame

_DEFAULT_ADDR = const(0x28)

_CHIP_ID = const(0x00)
_PAGE_ID = const(0x07)
_ACC_DATA = const(0x08)
_GYR_DATA = const(0x14)
_EUL_DATA = const(0x1A)
_UNIT_SEL = const(0x3B)
_OPR_MODE = const(0x3D)
_PWR_MODE = const(0x3E)

_BNO055_ID = const(0xA0)
_MODE_CONFIG = const(0x00)
_MODE_IMU = const(0x08)
_PWR_NORMAL = const(0x00)
# m/s^2, dps, degrees, Celsius, Windows orientation: fixed here so a previous program's settings
# (they survive a soft reset of the hub) cannot change the units.
_UNITS = const(0x00)

_BOOT_MS = const(850)  # datasheet: 650 ms power-on to configuration mode, plus margin
_TO_CONFIG_MS = const(20)  # any mode -> CONFIG takes 19 ms
_TO_FUSION_MS = const(10)  # CONFIG -> any operating mode takes 7 ms

_ENODEV = const(19)


class BNO055(HeadingFrame, IMU):
    """BNO055 at `address` (0x28, or 0x29 with ADR strapped high) on a machine.I2C or mux channel."""

    HEADING_SOURCE = "BNO055"

    def __init__(self, i2c, address=_DEFAULT_ADDR):
        self._i2c = i2c
        self._address = address
        self._buf = bytearray(6)
        self._wait_for_chip()
        self._write(_OPR_MODE, _MODE_CONFIG)
        time.sleep_ms(_TO_CONFIG_MS)
        self._write(_PAGE_ID, 0)
        self._write(_PWR_MODE, _PWR_NORMAL)
        self._write(_UNIT_SEL, _UNITS)
        self._write(_OPR_MODE, _MODE_IMU)
        time.sleep_ms(_TO_FUSION_MS)
        self._offset = self._raw_heading()

    def _write(self, reg, value):
        self._i2c.writeto_mem(self._address, reg, bytes((value,)))

    def _wait_for_chip(self):
        # Right after power-up the chip does not answer at all for ~650 ms.
        start = time.ticks_ms()
        while True:
            try:
                chip_id = self._i2c.readfrom_mem(self._address, _CHIP_ID, 1)[0]
                error = None
            except OSError as e:
                chip_id, error = None, e
            if chip_id == _BNO055_ID:
                return
            if time.ticks_diff(time.ticks_ms(), start) >= _BOOT_MS:
                break
            time.sleep_ms(10)
        if error is not None:
            raise OSError(
                _ENODEV,
                "no BNO055 answers at I2C address 0x%02X (%s): check SDA/SCL/power; a board with ADR "
                "strapped high is at address=0x29" % (self._address, error),
            )
        raise OSError(
            _ENODEV,
            "the chip at I2C address 0x%02X is not a BNO055: CHIP_ID (0x00) reads 0x%02X, expected 0xA0"
            % (self._address, chip_id),
        )

    def _vector(self, reg, lsb_per_unit):
        self._i2c.readfrom_mem_into(self._address, reg, self._buf)
        x, y, z = struct.unpack("<3h", self._buf)
        return (x / lsb_per_unit, y / lsb_per_unit, z / lsb_per_unit)

    def _raw_heading(self):
        self._i2c.readfrom_mem_into(self._address, _EUL_DATA, self._buf)
        return struct.unpack_from("<h", self._buf)[0] / 16

    def heading(self):
        """Body heading in degrees, wrapped to [-180, 180), clockwise-positive."""
        return _wrap(self._raw_heading() - self._offset)

    def reset_heading(self, angle=0):
        """Make the current pose read `angle` degrees.

        Refused while a drive base steers by this IMU: its controller holds a target in the
        current frame, and moving the frame under it makes the next move veer.
        """
        self._check_heading_free()
        self._offset = self._raw_heading() - angle

    def euler(self):
        """(heading, roll, pitch) in degrees; heading as heading()."""
        heading, roll, pitch = self._vector(_EUL_DATA, 16)
        return (_wrap(heading - self._offset), roll, pitch)

    def angular_velocity(self):
        """(x, y, z) gyro rates in deg/s, in the chip's frame."""
        return self._vector(_GYR_DATA, 16)

    def acceleration(self):
        """(x, y, z) acceleration in m/s^2, in the chip's frame."""
        return self._vector(_ACC_DATA, 100)

    def __repr__(self):
        return "BNO055(address=0x%02X)" % self._address


def _wrap(degrees):
    return (degrees + 180.0) % 360.0 - 180.0
