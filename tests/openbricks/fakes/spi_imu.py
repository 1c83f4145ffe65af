"""A register-level TDK ICM-45686 on the fake SPI bus.

SPI framing as the datasheet gives it: the first byte is the register
address with bit 7 set for a read; the chip answers the following bytes
from consecutive registers. Bank-0 registers modelled: sensor data
(0x00-0x0B, little-endian int16, accel then gyro), PWR_MGMT0 (0x10),
ACCEL_CONFIG0 (0x1B) / GYRO_CONFIG0 (0x1C) full-scale selects, WHO_AM_I
(0x72 = 0xE9), REG_MISC2 (0x7F) soft reset. A sensor that is powered off
reads -32768, the chip's "no data" value.

The scene is the robot, not the die: `yaw_rate_dps` is the body's turn rate
clockwise seen from above; a face-up chip reports it on gyro Z with the
right-hand (counter-clockwise-positive) sign, plus `gyro_bias_dps`.
Attach with `machine.board.attach_spi(cs_pin, chip)`.
"""

import struct

from . import clock

WHO_AM_I_VALUE = 0xE9
_GYRO_FS_DPS = (4000.0, 2000.0, 1000.0, 500.0, 250.0, 125.0, 62.5, 31.25, 15.625)
_ACCEL_FS_G = (32.0, 16.0, 8.0, 4.0, 2.0)
_NO_DATA = -32768


class ICM45686Chip:
    PWR_MGMT0, ACCEL_CONFIG0, GYRO_CONFIG0, WHO_AM_I, MISC2 = 0x10, 0x1B, 0x1C, 0x72, 0x7F

    def __init__(self, who_am_i=WHO_AM_I_VALUE):
        self.who_am_i = who_am_i
        self.yaw_rate_dps = 0.0
        self.gyro_bias_dps = 0.0
        self.gyro_xy_dps = (0.0, 0.0)
        self.accel_g = (0.0, 0.0, 1.0)
        self.face_up = True
        self.silent = False  # MISO floating: every byte reads 0xFF
        self.soft_resets = 0
        self.data_reads = 0
        self._reset_registers()
        self._reset_until_us = 0  # powered up long before the test starts

    def _reset_registers(self):
        self.regs = bytearray(128)
        self.regs[self.ACCEL_CONFIG0] = 0x06  # +-32 g, 800 Hz after reset
        self.regs[self.GYRO_CONFIG0] = 0x06  # +-4000 dps, 800 Hz
        self.regs[self.WHO_AM_I] = self.who_am_i
        self._reset_until_us = clock.now_us() + 1000  # registers unusable for 1 ms after a reset

    def gyro_fs_dps(self):
        return _GYRO_FS_DPS[self.regs[self.GYRO_CONFIG0] >> 4]

    def accel_fs_g(self):
        return _ACCEL_FS_G[(self.regs[self.ACCEL_CONFIG0] >> 4) & 0x07]

    def _data_bytes(self):
        self.data_reads += 1
        pwr = self.regs[self.PWR_MGMT0]
        accel_on = (pwr & 0x03) in (2, 3)
        gyro_on = ((pwr >> 2) & 0x03) in (2, 3)
        z_sign = -1.0 if self.face_up else 1.0
        gz = z_sign * self.yaw_rate_dps + self.gyro_bias_dps
        gyro = (self.gyro_xy_dps[0], self.gyro_xy_dps[1], gz)
        values = []
        for g in self.accel_g:
            values.append(_to_counts(g, self.accel_fs_g()) if accel_on else _NO_DATA)
        for w in gyro:
            values.append(_to_counts(w, self.gyro_fs_dps()) if gyro_on else _NO_DATA)
        return struct.pack("<6h", *values)

    def transfer(self, data):
        if self.silent:
            return b"\xff" * len(data)
        if clock.now_us() < self._reset_until_us:
            return b"\x00" * len(data)
        address = data[0] & 0x7F
        if data[0] & 0x80:
            out = bytearray(len(data))
            block = self._data_bytes() if address < 12 else b""
            for i in range(1, len(data)):
                reg = (address + i - 1) & 0x7F
                out[i] = block[reg] if reg < len(block) else self.regs[reg]
            return bytes(out)
        for i, value in enumerate(data[1:]):
            reg = (address + i) & 0x7F
            if reg == self.MISC2 and value & 0x02:
                self.soft_resets += 1
                self._reset_registers()
                continue
            if reg != self.WHO_AM_I:
                self.regs[reg] = value
        return b"\x00" * len(data)


def _to_counts(value, full_scale):
    return max(-32767, min(32767, int(round(value * 32768.0 / full_scale))))
