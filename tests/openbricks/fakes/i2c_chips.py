"""Register-level models of the I2C chips the sensor and display drivers talk to.

Each model answers the bytes a driver puts on the bus the way the datasheet
says the chip does: identity registers, the power-up and measurement timing
(against the virtual clock, so a driver that reads too early sees what real
silicon would show: stale zeros or a not-ready flag), and the scene the test
sets up (light on the colour sensor, a target in front of the range finder,
the robot's attitude under the IMU). Attach one with
`machine.board.attach_i2c(bus_id, address, chip)`, or behind a TCA9548A model
with `mux.attach(channel, address, chip)`.
"""

import struct

from . import clock
from .machine import board

EIO = 5
ENODEV = 19


def _elapsed_ms(since_us):
    return (clock.now_us() - since_us) / 1000


class RegisterChip:
    """A chip whose bus protocol is 'first byte(s) select a register, the rest read or write from there'.

    `regs` holds what reads return; subclasses compute live registers in `_read_reg` and react to
    writes in `_write_reg`. Every register write is logged in `writes` as (register, value).
    """

    ADDRESS_BYTES = 1
    SIZE = 256

    def __init__(self):
        self.regs = bytearray(self.SIZE) if self.ADDRESS_BYTES == 1 else {}
        self.pointer = 0
        self.writes = []

    # -- what subclasses customise -----------------------------------------------------------

    def _read_reg(self, reg):
        return self.regs[reg] if self.ADDRESS_BYTES == 1 else self.regs.get(reg, 0)

    def _write_reg(self, reg, value):
        self.regs[reg] = value

    def _next(self, reg):
        return (reg + 1) % self.SIZE if self.ADDRESS_BYTES == 1 else (reg + 1) & 0xFFFF

    # -- the bus side (called by the fake machine.I2C) ---------------------------------------

    def _select(self, address_bytes):
        reg = 0
        for b in address_bytes:
            reg = (reg << 8) | b
        return reg

    def write(self, data):
        n = self.ADDRESS_BYTES
        if len(data) < n:
            raise OSError(EIO)
        self.pointer = self._select(data[:n])
        for value in data[n:]:
            self.writes.append((self.pointer, value))
            self._write_reg(self.pointer, value)
            self.pointer = self._next(self.pointer)

    def read(self, nbytes):
        out = bytearray()
        for _ in range(nbytes):
            out.append(self._read_reg(self.pointer) & 0xFF)
            self.pointer = self._next(self.pointer)
        return bytes(out)

    def write_mem(self, reg, data, addrsize):
        self.write(reg.to_bytes(addrsize // 8, "big") + bytes(data))

    def read_mem(self, reg, nbytes, addrsize):
        self.write(reg.to_bytes(addrsize // 8, "big"))
        return self.read(nbytes)

    def written(self, reg):
        """Every value written to `reg`, oldest first."""
        return [v for r, v in self.writes if r == reg]


# --------------------------------------------------------------------------------------------
# TCA9548A: the 8-channel I2C switch


class TCA9548AChip:
    """The mux: one control register; bit n connects downstream channel n to the upstream bus.

    Connecting a channel really puts its devices on the upstream bus (board.i2c_devices), so a
    driver only reaches a sensor while its channel is selected, and two enabled channels with
    the same address collide (EIO) exactly as two chips fighting over SDA would.
    """

    def __init__(self, bus_id=0, address=0x70):
        self.bus_id = bus_id
        self.address = address
        self.control = 0
        self.control_writes = 0
        self.channels = [{} for _ in range(8)]  # channel -> {address: device}
        self._connected = {}  # address -> device we put on the upstream bus
        board.attach_i2c(bus_id, address, self)

    def attach(self, channel, address, device):
        self.channels[channel][address] = device
        self._reconnect()

    def write(self, data):
        if not data:
            return
        self.control = data[-1]
        self.control_writes += 1
        self._reconnect()

    def read(self, nbytes):
        return bytes([self.control]) * nbytes

    def write_mem(self, reg, data, addrsize):
        self.write(bytes([reg]) + bytes(data))

    def read_mem(self, reg, nbytes, addrsize):
        self.write(bytes([reg]))
        return self.read(nbytes)

    def power_cycle(self):
        """A brown-out of the mux alone: it comes back with every channel off."""
        self.control = 0
        self._reconnect()

    def _reconnect(self):
        bus = board.i2c_devices.setdefault(self.bus_id, {})
        for address in self._connected:
            if bus.get(address) is self._connected[address]:
                del bus[address]
        self._connected = {}
        for channel in range(8):
            if not self.control & (1 << channel):
                continue
            for address, device in self.channels[channel].items():
                if address in self._connected:
                    device = _Collision()
                self._connected[address] = device
        for address, device in self._connected.items():
            bus[address] = device


class _Collision:
    """Two same-address chips on enabled channels: every transfer is garbage."""

    def read(self, nbytes):
        raise OSError(EIO)

    def write(self, data):
        raise OSError(EIO)

    def read_mem(self, reg, nbytes, addrsize):
        raise OSError(EIO)

    def write_mem(self, reg, data, addrsize):
        raise OSError(EIO)


# --------------------------------------------------------------------------------------------
# TCS34725: RGB + clear light-to-digital converter


class TCS34725Chip(RegisterChip):
    """Command-byte protocol (bit 7 set, bits 6:5 = 01 for auto-increment), ENABLE/ATIME/CONTROL,
    ID 0x44, STATUS.AVALID once an integration cycle has completed, CRGB data little-endian.

    The scene: `light` = (clear, red, green, blue) counts that ONE 2.4 ms cycle at 1x gain would
    accumulate; the chip multiplies by cycles and gain and saturates at min(65535, 1024 x cycles).
    """

    ENABLE, ATIME, CONTROL, ID, STATUS, CDATAL = 0x00, 0x01, 0x0F, 0x12, 0x13, 0x14
    GAINS = (1, 4, 16, 60)

    def __init__(self, chip_id=0x44):
        super().__init__()
        self.regs[self.ATIME] = 0xFF
        self.regs[self.ID] = chip_id
        self.light = (0, 0, 0, 0)
        self._enabled_us = None  # when PON+AEN were both set
        self._pon_us = None
        self.bad_commands = 0
        self._auto_increment = False

    def _command(self, byte):
        if not byte & 0x80:
            # Not a command byte: the chip ignores the transaction's register selection.
            self.bad_commands += 1
            raise OSError(EIO)
        # TYPE 01 walks the register pointer; TYPE 00 ("repeated byte") keeps reading one register.
        self._auto_increment = (byte & 0x60) == 0x20
        return byte & 0x1F

    def _next(self, reg):
        return (reg + 1) & 0xFF if self._auto_increment else reg

    def write(self, data):
        if not data:
            return
        self.pointer = self._command(data[0])
        for value in data[1:]:
            self.writes.append((self.pointer, value))
            self._write_reg(self.pointer, value)
            self.pointer = self._next(self.pointer)

    def write_mem(self, reg, data, addrsize):
        self.write(bytes([reg]) + bytes(data))

    def _write_reg(self, reg, value):
        self.regs[reg] = value
        if reg == self.ENABLE:
            now = clock.now_us()
            if value & 0x01 and self._pon_us is None:
                self._pon_us = now
            if not value & 0x01:
                self._pon_us = None
            # Integration starts on AEN, but only counts after the 2.4 ms PON warm-up.
            self._enabled_us = now if (value & 0x03) == 0x03 else None

    def cycles(self):
        return 256 - self.regs[self.ATIME]

    def gain(self):
        return self.GAINS[self.regs[self.CONTROL] & 0x03]

    def max_count(self):
        return min(65535, 1024 * self.cycles())

    def _integrated(self):
        if self._enabled_us is None or self._pon_us is None:
            return False
        warm_up_done_ms = max(0.0, 2.4 - (self._enabled_us - self._pon_us) / 1000)
        return _elapsed_ms(self._enabled_us) >= warm_up_done_ms + 2.4 * self.cycles()

    def counts(self):
        if not self._integrated():
            return (0, 0, 0, 0)
        scale = self.cycles() * self.gain()
        cap = self.max_count()
        return tuple(min(cap, int(v * scale)) for v in self.light)

    def _read_reg(self, reg):
        if reg == self.STATUS:
            return 0x01 if self._integrated() else 0x00
        if self.CDATAL <= reg < self.CDATAL + 8:
            index, high = divmod(reg - self.CDATAL, 2)
            value = self.counts()[index]
            return (value >> 8) if high else (value & 0xFF)
        return self.regs[reg]


# --------------------------------------------------------------------------------------------
# BNO055: 9-axis IMU with on-chip fusion (IMU mode = accelerometer + gyro)


class BNO055Chip(RegisterChip):
    """Page-0 register map: CHIP_ID 0xA0, OPR_MODE with the datasheet's switching times,
    fusion outputs (Euler 1/16 deg, gyro 1/16 dps, acceleration 1/100 m/s^2) only while a
    fusion mode has been running for 7 ms, no answer at all during the 650 ms power-on boot.

    The scene: `heading_deg` (the chip's own 0..360 CW compass-style yaw, relative to where fusion
    started), `roll_deg`, `pitch_deg`, `gyro_dps` (x, y, z), `accel_ms2` (x, y, z).
    """

    CHIP_ID, PAGE_ID, ACC_DATA, GYR_DATA, EUL_DATA = 0x00, 0x07, 0x08, 0x14, 0x1A
    UNIT_SEL, OPR_MODE, PWR_MODE, SYS_TRIGGER = 0x3B, 0x3D, 0x3E, 0x3F
    CONFIG_MODE = 0x00
    BOOT_MS = 650

    def __init__(self, boot_ms=0):
        super().__init__()
        self.regs[self.CHIP_ID] = 0xA0
        self.regs[0x01] = 0xFB
        self.regs[0x02] = 0x32
        self.regs[0x03] = 0x0F
        self.regs[self.UNIT_SEL] = 0x80  # power-on default: Android orientation, m/s^2, dps, deg
        self._booted_at_us = clock.now_us() + int(boot_ms * 1000)
        self._mode_since_us = clock.now_us()
        self.heading_deg = 0.0
        self.roll_deg = 0.0
        self.pitch_deg = 0.0
        self.gyro_dps = (0.0, 0.0, 0.0)
        self.accel_ms2 = (0.0, 0.0, 9.81)

    def _alive(self):
        if clock.now_us() < self._booted_at_us:
            raise OSError(ENODEV)

    def write(self, data):
        self._alive()
        super().write(data)

    def read(self, nbytes):
        self._alive()
        return super().read(nbytes)

    def _write_reg(self, reg, value):
        if reg == self.SYS_TRIGGER and value & 0x20:
            # RST_SYS: the chip reboots and forgets its configuration.
            self.__init__(boot_ms=self.BOOT_MS)
            return
        self.regs[reg] = value
        if reg == self.OPR_MODE:
            self._mode_since_us = clock.now_us()

    def mode(self):
        return self.regs[self.OPR_MODE] & 0x0F

    def fusing(self):
        return self.mode() != self.CONFIG_MODE and _elapsed_ms(self._mode_since_us) >= 7

    def _block(self, reg):
        if self.ACC_DATA <= reg < self.ACC_DATA + 6:
            return self.ACC_DATA, [v * 100 for v in self.accel_ms2]
        if self.GYR_DATA <= reg < self.GYR_DATA + 6:
            return self.GYR_DATA, [v * 16 for v in self.gyro_dps]
        if self.EUL_DATA <= reg < self.EUL_DATA + 6:
            heading = self.heading_deg % 360.0
            return self.EUL_DATA, [heading * 16, self.roll_deg * 16, self.pitch_deg * 16]
        return None, None

    def _read_reg(self, reg):
        base, values = self._block(reg)
        if base is None:
            return self.regs[reg]
        if not self.fusing():
            return 0
        raw = struct.pack("<3h", *[int(round(v)) for v in values])
        return raw[reg - base]


# --------------------------------------------------------------------------------------------
# VL53L0X and VL53L1X: time-of-flight range finders


class VL53L0XChip(RegisterChip):
    """8-bit registers, model ID 0xEE at 0xC0. SYSRANGE_START (0x00) bit 0 starts one ranging that
    completes `ranging_ms` later; RESULT_INTERRUPT_STATUS (0x13) then reads 0x01 (new sample) until
    SYSTEM_INTERRUPT_CLEAR (0x0B); the range sits big-endian at 0x1E. `distance_mm` is the target
    (None = nothing in range, which the chip reports as 8190)."""

    SYSRANGE_START, INTERRUPT_CLEAR, INTERRUPT_STATUS, RANGE_MM = 0x00, 0x0B, 0x13, 0x1E

    def __init__(self, ranging_ms=33):
        super().__init__()
        self.regs[0xC0] = 0xEE
        self.regs[0xC1] = 0xAA
        self.regs[0xC2] = 0x10
        self.ranging_ms = ranging_ms
        self.distance_mm = 500
        self.stalled = False  # a wedged chip never finishes a ranging
        self.rangings = 0
        self._started_us = None
        self._result = 0
        self._ready = False

    def _write_reg(self, reg, value):
        self.regs[reg] = value
        if reg == self.SYSRANGE_START and value & 0x01:
            self._started_us = clock.now_us()
            self.rangings += 1
        elif reg == self.INTERRUPT_CLEAR and value & 0x01:
            self._ready = False

    def _update(self):
        if self._started_us is not None and not self.stalled:
            if _elapsed_ms(self._started_us) >= self.ranging_ms:
                self._started_us = None
                self._result = 8190 if self.distance_mm is None else int(self.distance_mm)
                self._ready = True

    def _read_reg(self, reg):
        self._update()
        if reg == self.INTERRUPT_STATUS:
            return 0x01 if self._ready else 0x00
        if reg in (self.RANGE_MM, self.RANGE_MM + 1):
            return (self._result >> 8) if reg == self.RANGE_MM else (self._result & 0xFF)
        if reg == self.SYSRANGE_START:
            return 0x01 if self._started_us is not None else 0x00
        return self.regs[reg]


class VL53L1XChip(RegisterChip):
    """16-bit register addresses, model ID 0xEACC at 0x010F (0xEBAA for the VL53L4CD), firmware
    boot flag at 0x00E5. SYSTEM_MODE_START (0x0087) = 0x40 starts a ranging; GPIO_TIO_HV_STATUS
    (0x0031) bit 0 reads 1 until data is ready (active-low interrupt), then 0 until
    SYSTEM_INTERRUPT_CLEAR (0x0086) bit 0 is written. RESULT_RANGE_STATUS (0x0089) low 5 bits read
    9 for a valid range, 4 (signal fail) when nothing is in range; the range is big-endian at
    0x0096."""

    ADDRESS_BYTES = 2
    INTERRUPT_CLEAR, MODE_START, TIO_HV_STATUS, RANGE_STATUS, RANGE_MM = 0x86, 0x87, 0x31, 0x89, 0x96
    FIRMWARE_STATUS = 0xE5

    def __init__(self, model_id=0xEACC, boot_ms=2, ranging_ms=50):
        super().__init__()
        self.regs[0x010F] = model_id >> 8
        self.regs[0x0110] = model_id & 0xFF
        self.ranging_ms = ranging_ms
        self.distance_mm = 1200
        self.rangings = 0
        self._booted_at_us = clock.now_us() + int(boot_ms * 1000)
        self._started_us = None
        self._ready = False
        self._result = (0, 0)  # (range status, mm)

    def _write_reg(self, reg, value):
        self.regs[reg] = value
        if reg == self.MODE_START and value == 0x40:
            self._started_us = clock.now_us()
            self.rangings += 1
        elif reg == self.INTERRUPT_CLEAR and value & 0x01:
            self._ready = False

    def finish_late(self, distance_mm):
        """A ranging the driver gave up on completes now, leaving a stale result pending."""
        self._result = (9, distance_mm)
        self._ready = True

    def _update(self):
        if self._started_us is not None and _elapsed_ms(self._started_us) >= self.ranging_ms:
            self._started_us = None
            if self.distance_mm is None:
                self._result = (4, 0)
            else:
                self._result = (9, int(self.distance_mm))
            self._ready = True

    def _read_reg(self, reg):
        self._update()
        if reg == self.FIRMWARE_STATUS:
            return 0x01 if clock.now_us() >= self._booted_at_us else 0x00
        if reg == self.TIO_HV_STATUS:
            return 0x00 if self._ready else 0x01
        if reg == self.RANGE_STATUS:
            return self._result[0]
        if reg in (self.RANGE_MM, self.RANGE_MM + 1):
            mm = self._result[1]
            return (mm >> 8) if reg == self.RANGE_MM else (mm & 0xFF)
        return self.regs.get(reg, 0)


# --------------------------------------------------------------------------------------------
# SSD1306: 128x64 / 128x32 OLED controller


class SSD1306Chip:
    """The controller's I2C protocol: a control byte (0x00 command stream, 0x80 one command,
    0x40 data stream) then commands with their argument bytes, or GDDRAM data written at the
    column/page pointer inside the window set by 0x21/0x22 (horizontal addressing).

    `lit(x, y)` is what a person looking at the panel sees: nothing unless the charge pump is on
    and the display is switched on, GDDRAM mapped through the segment remap and COM scan
    direction (0xA1 + 0xC8 is the upright orientation of the common modules), inverted by 0xA7.
    """

    ARGS = {
        0x20: 1,
        0x21: 2,
        0x22: 2,
        0x81: 1,
        0x8D: 1,
        0xA8: 1,
        0xD3: 1,
        0xD5: 1,
        0xD9: 1,
        0xDA: 1,
        0xDB: 1,
    }

    def __init__(self, height=64):
        self.height = height
        self.pages = height // 8
        self.gddram = [bytearray(128) for _ in range(8)]
        self.display_on = False
        self.charge_pump = False
        self.contrast = 0x7F
        self.inverted = False
        self.seg_remap = False
        self.com_reversed = False
        self.addressing = 0x02  # page addressing after reset
        self.multiplex = 63
        self.col_window = (0, 127)
        self.page_window = (0, 7)
        self.col = 0
        self.page = 0
        self.commands = []  # (opcode, args) in order
        self.data_bytes = 0
        self._pending = None  # (opcode, args collected so far)

    def write(self, data):
        if not data:
            return
        control, payload = data[0], data[1:]
        if control == 0x40:
            for b in payload:
                self._data(b)
        elif control in (0x00, 0x80):
            for b in payload:
                self._command_byte(b)
        else:
            raise OSError(EIO)

    def read(self, nbytes):
        # Status byte: bit 6 = display off.
        return bytes([0x00 if self.display_on else 0x40]) * nbytes

    def write_mem(self, reg, data, addrsize):
        self.write(bytes([reg]) + bytes(data))

    def read_mem(self, reg, nbytes, addrsize):
        return self.read(nbytes)

    def _command_byte(self, b):
        if self._pending is not None:
            opcode, args = self._pending
            args.append(b)
            if len(args) == self.ARGS[opcode]:
                self._pending = None
                self._execute(opcode, args)
            return
        if b in self.ARGS:
            self._pending = (b, [])
            return
        self._execute(b, [])

    def _execute(self, op, args):
        self.commands.append((op, tuple(args)))
        if op == 0xAE:
            self.display_on = False
        elif op == 0xAF:
            self.display_on = True
        elif op == 0x8D:
            self.charge_pump = bool(args[0] & 0x04)
        elif op == 0x81:
            self.contrast = args[0]
        elif op in (0xA6, 0xA7):
            self.inverted = op == 0xA7
        elif op in (0xA0, 0xA1):
            self.seg_remap = op == 0xA1
        elif op in (0xC0, 0xC8):
            self.com_reversed = op == 0xC8
        elif op == 0x20:
            self.addressing = args[0] & 0x03
        elif op == 0xA8:
            self.multiplex = args[0] & 0x3F
        elif op == 0x21:
            self.col_window = (args[0] & 0x7F, args[1] & 0x7F)
            self.col = self.col_window[0]
        elif op == 0x22:
            self.page_window = (args[0] & 0x07, args[1] & 0x07)
            self.page = self.page_window[0]

    def _data(self, b):
        self.data_bytes += 1
        self.gddram[self.page][self.col] = b
        if self.addressing != 0x00:
            self.col = min(127, self.col + 1)
            return
        if self.col < self.col_window[1]:
            self.col += 1
            return
        self.col = self.col_window[0]
        self.page = self.page + 1 if self.page < self.page_window[1] else self.page_window[0]

    def lit(self, x, y):
        if not (self.display_on and self.charge_pump):
            return False
        column = x if self.seg_remap else 127 - x
        row = y if self.com_reversed else (self.multiplex - y)
        on = bool(self.gddram[row // 8][column] >> (row % 8) & 1)
        return on != self.inverted

    def lit_pixels(self):
        return [(x, y) for y in range(self.height) for x in range(128) if self.lit(x, y)]
