"""A serial-bus engine for the tests: the contract of `_openbricks_native.serial_bus(uart_id)`.

On the hub the engine is C code on the hard tick and in the simulator an emulation over MuJoCo
wheels; both take over a UART that a DriveBase handed over and drive the adopted servos in open-loop
duty mode. This one does the same over the fake board: it opens the UART again after the hand-over
and speaks real SCS packets to the fake servos (`fakes.scs_servo`), so a servo that stops answering
shows up exactly as on a bus: failed reads, counted per slot.

Its motor IO is Python callables (`read_angle`, `write_duty`, `coast`), so the drive base's
controller calls into Python every tick here; the contract is the same.

    serial_bus_engine.install()     # _openbricks_native.serial_bus now exists
    ...
    serial_bus_engine.uninstall()   # and now it does not ("no engine on this runtime")
"""

import machine

_PING = 0x01
_READ = 0x02
_WRITE = 0x03
_REG_MODE = 0x21
_REG_TORQUE_ENABLE = 0x28
_REG_GOAL_TIME = 0x2C  # the signed duty, 0.1 % with the sign in bit 10, in mode 2
_REG_PRESENT_POSITION = 0x38  # position, speed, load: one 6-byte read
_MODE_WHEEL = 1
_MODE_DUTY = 2
_DEG_PER_COUNT = 360.0 / 4096
_WINDOW = 65535  # multi-turn present position wraps in a +-32767 sign-magnitude window

_engines = {}


def _sign_magnitude(value, sign_bit):
    value = int(round(value))
    limit = (1 << sign_bit) - 1
    return min(-value, limit) | (1 << sign_bit) if value < 0 else min(value, limit)


def _from_sign_magnitude(raw, sign_bit):
    magnitude = raw & ((1 << sign_bit) - 1)
    return -magnitude if raw & (1 << sign_bit) else magnitude


def _packet(servo_id, instruction, params):
    body = bytes((servo_id, len(params) + 2, instruction)) + bytes(params)
    return b"\xff\xff" + body + bytes(((~sum(body)) & 0xFF,))


class SlotIO:
    """One adopted servo, in the adopting motor's user frame (its invert applied)."""

    def __init__(self, engine, servo_id, invert):
        self.engine = engine
        self.servo_id = servo_id
        self.sign = -1 if invert else 1
        self.replies = 0
        self.failed_reads = 0
        self.failed_in_a_row = 0
        self.reads = 0
        self._counts = None
        self._last_raw = None
        self.speed_dps = 0.0
        self.load_pct = 0.0
        self.angle_deg = None  # latest reading; None after a failed read
        self.duty_pct = None  # what the servo was told last: a duty, or None while coasting
        self._torque = None

    def read_angle(self):
        """One feedback read (position, speed and load); the angle in degrees, or None if silent."""
        self.reads += 1
        data = self.engine.transact(self.servo_id, _READ, (_REG_PRESENT_POSITION, 6))
        if data is None or len(data) != 6:
            self.failed_reads += 1
            self.failed_in_a_row += 1
            self.angle_deg = None
            return None
        self.replies += 1
        self.failed_in_a_row = 0
        raw = _from_sign_magnitude(data[0] | data[1] << 8, 15)
        if self._last_raw is None:
            self._counts = raw
        else:
            step = raw - self._last_raw
            if step > _WINDOW // 2:
                step -= _WINDOW
            elif step < -(_WINDOW // 2):
                step += _WINDOW
            self._counts += step
        self._last_raw = raw
        self.speed_dps = self.sign * _from_sign_magnitude(data[2] | data[3] << 8, 15) * _DEG_PER_COUNT
        self.load_pct = self.sign * _from_sign_magnitude(data[4] | data[5] << 8, 10) / 10
        self.angle_deg = self.sign * self._counts * _DEG_PER_COUNT
        return self.angle_deg

    def write_duty(self, duty_pct):
        duty_pct = max(-100.0, min(100.0, duty_pct))
        raw = _sign_magnitude(self.sign * duty_pct * 10, 10)
        if self.duty_pct is None or raw != _sign_magnitude(self.sign * self.duty_pct * 10, 10):
            self.engine.transact(self.servo_id, _WRITE, (_REG_GOAL_TIME, raw & 0xFF, raw >> 8))
        self.duty_pct = duty_pct
        if self._torque is not True:
            self.engine.transact(self.servo_id, _WRITE, (_REG_TORQUE_ENABLE, 1))
            self._torque = True

    def coast(self):
        self.duty_pct = None
        if self._torque is not False:
            self.engine.transact(self.servo_id, _WRITE, (_REG_TORQUE_ENABLE, 0))
            self._torque = False


class FakeBusEngine:
    def __init__(self, uart_id):
        self.uart_id = uart_id
        self.uart = machine.UART(uart_id, baudrate=1_000_000, tx=14, rx=41)
        self.slots = []  # SlotIO, or None once released

    def transact(self, servo_id, instruction, params):
        """Send one packet; the reply's parameters, or None when no valid reply came."""
        uart = self.uart
        if uart.any():
            uart.read()
        uart.write(_packet(servo_id, instruction, params))
        reply = uart.read()
        if not reply or len(reply) < 6 or reply[:2] != b"\xff\xff" or reply[2] != servo_id:
            return None
        length = reply[3]
        body = reply[2 : 4 + length - 1]
        if len(reply) < 4 + length or ((~sum(body)) & 0xFF) != reply[3 + length]:
            return None
        return bytes(body[3:])

    # --- the engine contract ------------------------------------------------------------------

    def adopt(self, servo_id, invert=False):
        io = SlotIO(self, servo_id, invert)
        io.coast()
        self.transact(servo_id, _WRITE, (_REG_GOAL_TIME, 0, 0))
        self.transact(servo_id, _WRITE, (_REG_MODE, _MODE_DUTY))
        self.slots.append(io)
        return len(self.slots) - 1

    def _io(self, slot):
        io = self.slots[slot] if 0 <= slot < len(self.slots) else None
        if io is None:
            raise ValueError("slot %r is not an adopted servo on UART%d" % (slot, self.uart_id))
        return io

    def motor_io(self, slot):
        return self._io(slot)

    def angle_deg(self, slot):
        return self._io(slot).read_angle()

    def speed_dps(self, slot):
        return self._io(slot).speed_dps

    def load_pct(self, slot):
        return self._io(slot).load_pct

    def stats(self, slot):
        io = self._io(slot)
        return (io.replies, io.failed_reads, io.failed_in_a_row)

    def release(self, slot):
        io = self._io(slot)
        io.coast()
        self.transact(io.servo_id, _WRITE, (_REG_MODE, _MODE_WHEEL))
        self.slots[slot] = None


def serial_bus(uart_id):
    engine = _engines.get(uart_id)
    if engine is None:
        engine = _engines[uart_id] = FakeBusEngine(uart_id)
    return engine


def install():
    """Give `_openbricks_native` a serial_bus() backed by fresh engines."""
    import _openbricks_native

    _engines.clear()
    _openbricks_native.serial_bus = serial_bus


def uninstall():
    import _openbricks_native

    _engines.clear()
    if hasattr(_openbricks_native, "serial_bus"):
        del _openbricks_native.serial_bus


def engine(uart_id=1):
    """The engine serving `uart_id` (after a DriveBase asked for it)."""
    return _engines[uart_id]
