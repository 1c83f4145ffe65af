"""Feetech ST-3215 serial-bus servos: the SCS bus, a position servo, a wheel motor, synced writes.

Every servo on one UART shares one `_SCServoBus` (a registry keyed by UART
id), so an ST-3215 arm and two ST-3032 wheels can sit on one daisy chain. The
transactions (retries, echo, timeouts) are run here in Python; the packets are
built and parsed by the firmware's SCS codec (`_openbricks_native.scs`), the
one the hard-tick engine a DriveBase hands the UART to speaks.

Packet: 0xFF 0xFF ID LEN INSTR PARAMS... CHECKSUM, LEN = len(PARAMS) + 2,
CHECKSUM = ~(ID + LEN + INSTR + sum(PARAMS)) & 0xFF. A reply carries the
servo's status error flags where the request had its instruction.

Registers used (STS memory map): the angle limits (both 0 = multi-turn), mode
(0 position, 1 wheel, 2 open-loop duty, 3 step), torque enable, acceleration
(100 steps/s^2 units), goal position (a signed relative step in mode 3), goal
time (the signed duty in mode 2), goal speed, torque limit (0.1 %), present
position (steps still to go in mode 3), present speed and present load (0.1 %
of stall). Their addresses, the instructions and the modes are the C codec's
(`_openbricks_native.scs`, firmware/native/scs.h): one map for the firmware's
bus engine, the simulator's servos and this driver.
"""

import time

from micropython import const

from openbricks import _native, estop, pins
from openbricks.interfaces import Motor, Servo
from openbricks.parameters import Stop, then_name

# The codec's namespace: bound once, as every register access reads it. None on an interpreter
# without the cores (the tests' WebAssembly MicroPython), where this module still imports and
# constructing a servo says what is missing.
_scs = _native.get("scs")

# steps_per_dps default: the goal/present speed registers count encoder steps per second.
_DEFAULT_STEPS_PER_DPS = None
# One step write may cover +-7 turns (the STS multi-turn envelope); longer moves are chained.
_MAX_STEP_TURNS = const(7)

# A step has parked once it is within tolerance and turning slower than this (about 4 deg/s).
_PARKED_CPS = const(50)

_REPLY_TIMEOUT_US = const(3000)
_ATTEMPTS = const(2)

_FAULT_NAMES = ("voltage", "angle sensor", "temperature", "current", "angle", "overload")


def _codec():
    """The SCS codec of the native cores, or the ImportError that says this build has none."""
    return _native.scs if _scs is None else _scs


def _sign_magnitude(value, sign_bit):
    value = int(round(value))
    limit = (1 << sign_bit) - 1
    if value < 0:
        return min(-value, limit) | (1 << sign_bit)
    return min(value, limit)


def _from_sign_magnitude(raw, sign_bit):
    magnitude = raw & ((1 << sign_bit) - 1)
    return -magnitude if raw & (1 << sign_bit) else magnitude


def _u16(data, i):
    return data[i] | (data[i + 1] << 8)


def _parse_reply(buf, servo_id):
    """(status, params) once `buf` holds a valid reply from `servo_id`; None if incomplete; False if bad."""
    reply = _scs.decode_status(buf)
    if reply.result == "need_more":
        return None
    if reply.result != "ok" or reply.id != servo_id:
        return False
    return reply.error, bytes(reply.params)


def not_responding_message(label, servo_id, slot, where, replies, failed, in_a_row):
    """The one wording of the silent-servo error, shared with whoever runs the bus (a DriveBase)."""
    ident = "servo id %d" % servo_id if slot is None else "servo id %d, slot %d" % (servo_id, slot)
    return (
        "motor is not responding on the bus: %s (%s) on %s - %d replies, %d failed reads (%d in a row). "
        "Check the servo's power and TX/RX wiring, and that it really has that bus id - "
        "`openbricks servo-id --scan` lists the ids actually answering on the bus."
        % (label, ident, where, replies, failed, in_a_row)
    )


class _SCServoBus:
    """One half-duplex UART carrying SCS packets; shared by every servo wired to it."""

    _by_uart = {}

    @classmethod
    def for_uart(cls, uart_id, tx, rx, baud, dir_pin):
        bus = cls._by_uart.get(uart_id)
        if bus is None:
            bus = cls(uart_id, tx, rx, baud, dir_pin)
            cls._by_uart[uart_id] = bus
        elif (bus.tx, bus.rx, bus.baud, bus.dir_pin) != (tx, rx, baud, dir_pin):
            raise ValueError(
                "UART%d is already the servo bus on tx=%s rx=%s baud=%d dir_pin=%s; every servo on one "
                "UART shares its wiring, so construct this one with the same tx/rx/baud/dir_pin"
                % (uart_id, bus.tx, bus.rx, bus.baud, bus.dir_pin)
            )
        else:
            bus._claim_pins()  # the launcher drops claims between programs; the bus lives on
        return bus

    def __init__(self, uart_id, tx, rx, baud, dir_pin):
        self.uart_id = uart_id
        self.tx = tx
        self.rx = rx
        self.baud = baud
        self.dir_pin = dir_pin
        self.handed_over = False
        self.devices = []  # servos constructed on this bus, for adoption and diagnostics
        self._stats = {}  # servo id -> [replies, failed reads, failed in a row]
        self._uart = None
        self._dir = None
        self._claim_pins()
        from machine import UART

        self._uart = UART(uart_id, baudrate=baud, tx=tx, rx=rx, timeout=0)
        if dir_pin is not None:
            from machine import Pin

            self._dir = Pin(dir_pin, Pin.OUT, value=0)

    def _claim_pins(self):
        name = "servo bus UART%d" % self.uart_id
        pins.claim(self.tx, name + " TX", owner=name)
        pins.claim(self.rx, name + " RX", owner=name, output=False)
        if self.dir_pin is not None:
            pins.claim(self.dir_pin, name + " direction", owner=name)

    def where(self):
        return "UART%d tx=%s rx=%s" % (self.uart_id, self.tx, self.rx)

    def stats(self, servo_id):
        """(replies, failed reads, failed reads in a row) for `servo_id` on this bus."""
        return tuple(self._stats.get(servo_id, (0, 0, 0)))

    def hand_over(self):
        """Close the UART for a new owner (a DriveBase's native bus engine) and return its wiring.

        Afterwards every Python transaction on this bus raises instead of
        talking into a UART it no longer owns; the pins stay claimed by the bus.
        """
        self._check_open()
        self._uart.deinit()
        self._uart = None
        self.handed_over = True
        return self.uart_id, self.tx, self.rx, self.baud, self.dir_pin

    def close(self):
        """Release the UART and its pins (tests, and a program that is done with the bus)."""
        if self._uart is not None:
            self._uart.deinit()
            self._uart = None
        name = "servo bus UART%d" % self.uart_id
        for pin in (self.tx, self.rx, self.dir_pin):
            if pin is not None and pins.owner_of(pin) is not None and pins.owner_of(pin)[1] == name:
                pins.release(pin, name)
        if _SCServoBus._by_uart.get(self.uart_id) is self:
            del _SCServoBus._by_uart[self.uart_id]

    def _check_open(self):
        if self.handed_over:
            raise OSError(
                "UART%d belongs to the DriveBase's native bus engine since it adopted its wheels; "
                "drive those motors through the DriveBase or the motor objects it adopted" % self.uart_id
            )
        if self._uart is None:
            raise OSError("the servo bus on UART%d was closed" % self.uart_id)

    def _send(self, data):
        uart = self._uart
        if uart.any():
            uart.read()  # a late reply to an earlier request must not be taken for this one's
        if self._dir is not None:
            self._dir.value(1)
        uart.write(data)
        if self._dir is not None:
            while not uart.txdone():
                pass
            self._dir.value(0)

    def _receive(self, servo_id, sent):
        """The reply to `sent`, skipping its echo on adapters that hear their own TX; None on timeout."""
        uart = self._uart
        buf = b""
        echo = None
        deadline = time.ticks_add(time.ticks_us(), _REPLY_TIMEOUT_US)
        while True:
            waiting = uart.any()
            if waiting:
                buf += uart.read(waiting)
                if echo is None and buf[: len(sent)] == sent:
                    echo, buf = buf[: len(sent)], buf[len(sent) :]
                reply = _parse_reply(buf, servo_id)
                if reply is False:
                    return None
                if reply is not None:
                    return reply
            if time.ticks_diff(deadline, time.ticks_us()) <= 0:
                if echo is not None:
                    # What looked like our echo was the reply: a ping answered with status 1
                    # (voltage error) is byte-identical to the ping itself.
                    return _parse_reply(echo, servo_id) or None
                return None
            time.sleep_us(50)

    def request(self, servo_id, instr, params, attempts=_ATTEMPTS):
        """Send one instruction and return (status, reply params), or None if no valid reply came."""
        self._check_open()
        sent = _scs.frame(servo_id, instr, params)
        stats = self._stats.get(servo_id)
        if stats is None:
            stats = self._stats[servo_id] = [0, 0, 0]
        for _ in range(attempts):
            self._send(sent)
            reply = self._receive(servo_id, sent)
            if reply is not None:
                stats[0] += 1
                stats[2] = 0
                return reply
            stats[1] += 1
            stats[2] += 1
        return None

    def ping(self, servo_id):
        return self.request(servo_id, _scs.PING, b"") is not None

    def read(self, servo_id, address, length):
        """(status, data) or None."""
        reply = self.request(servo_id, _scs.READ, bytes((address, length)))
        if reply is None or len(reply[1]) != length:
            return None
        return reply

    def write(self, servo_id, address, data, attempts=_ATTEMPTS):
        """Status byte of the acknowledgement, or None if the servo never acknowledged."""
        reply = self.request(servo_id, _scs.WRITE, bytes((address,)) + bytes(data), attempts)
        return None if reply is None else reply[0]

    def sync_write(self, address, width, items):
        """One SYNC WRITE: every (servo id, `width` bytes) in `items` lands at the same packet boundary."""
        self._check_open()
        params = bytearray((address, width))
        for servo_id, data in items:
            if len(data) != width:
                raise ValueError(
                    "sync write of %d bytes got %d for servo id %d" % (width, len(data), servo_id)
                )
            params.append(servo_id)
            params.extend(data)
        self._send(_scs.frame(_scs.BROADCAST_ID, _scs.SYNC_WRITE, params))


def forget_buses():
    """Close every servo bus and release its pins; the next servo constructed opens a fresh one."""
    for bus in list(_SCServoBus._by_uart.values()):
        bus.close()


class _BusServo:
    """What ST3215 and ST3215Motor share: the bus, the id, error reporting, pings."""

    def _attach(self, servo_id, uart_id, tx, rx, baud, dir_pin):
        scs = _codec()
        if not isinstance(servo_id, int) or not 0 <= servo_id <= scs.MAX_SERVO_ID:
            raise ValueError(
                "servo_id=%r: bus ids are 0..%d (%d is broadcast)"
                % (servo_id, scs.MAX_SERVO_ID, scs.BROADCAST_ID)
            )
        self.servo_id = servo_id
        self.bus = _SCServoBus.for_uart(uart_id, tx, rx, baud, dir_pin)
        self.side = None  # set by an adopter, e.g. "left wheel"; names the motor in errors
        self.slot = None
        self._faults = 0
        if not self.bus.ping(servo_id):
            raise self._silent()
        self.bus.devices.append(self)

    def set_label(self, side, slot=None):
        """Name this servo in error messages the way its owner knows it ("right wheel", slot 1)."""
        self.side = side
        self.slot = slot

    def _silent(self):
        replies, failed, in_a_row = self.bus.stats(self.servo_id)
        label = self.side or type(self).__name__
        return OSError(
            not_responding_message(
                label, self.servo_id, self.slot, self.bus.where(), replies, failed, in_a_row
            )
        )

    def _note_status(self, status):
        self._faults = status
        if status & _scs.FLAG_OVERLOAD:
            self._torque = False  # overload protection unloaded the servo; the next command re-arms it

    def _read(self, address, length):
        reply = self.bus.read(self.servo_id, address, length)
        if reply is None:
            return None
        self._note_status(reply[0])
        return reply[1]

    def _write(self, address, data, attempts=_ATTEMPTS):
        status = self.bus.write(self.servo_id, address, data, attempts)
        if status is None:
            raise self._silent()
        self._note_status(status)

    def ping(self):
        """True if the servo answers on the bus."""
        return self.bus.ping(self.servo_id)

    def faults(self):
        """Names of the error flags in the servo's last reply, e.g. ("overload",); () when healthy."""
        return tuple(name for bit, name in enumerate(_FAULT_NAMES) if self._faults & (1 << bit))


class ST3215(_BusServo, Servo):
    """One ST-3215 in position mode (Servo interface), for grippers, lifts and turrets.

    `min_raw..max_raw` (register counts) span `range_deg` degrees; they are also
    written as the servo's angle limits, so the horn cannot be driven past them.
    """

    STALL_TORQUE_MNM = 2940.0

    def __init__(
        self,
        servo_id,
        uart_id=1,
        tx=14,
        rx=41,
        baud=1_000_000,
        dir_pin=None,
        min_raw=0,
        max_raw=4095,
        range_deg=360,
    ):
        if not 0 <= min_raw < max_raw <= 4095:
            raise ValueError(
                "min_raw=%r, max_raw=%r: need 0 <= min_raw < max_raw <= 4095" % (min_raw, max_raw)
            )
        if range_deg <= 0:
            raise ValueError("range_deg=%r: the span of min_raw..max_raw must be > 0 degrees" % (range_deg,))
        self.min_raw = min_raw
        self.max_raw = max_raw
        self.range_deg = range_deg
        self._attach(servo_id, uart_id, tx, rx, baud, dir_pin)
        self._write(_scs.REG_MIN_ANGLE, bytes((min_raw & 0xFF, min_raw >> 8, max_raw & 0xFF, max_raw >> 8)))
        self._write(_scs.REG_MODE, bytes((_scs.MODE_POSITION,)))
        estop.on_engage(self.coast)

    def _raw_for(self, angle_deg):
        return int(round(self.min_raw + angle_deg * (self.max_raw - self.min_raw) / self.range_deg))

    def move_to(self, angle_deg, speed=None, wait=True):
        """Move to `angle_deg` (0..range_deg); `speed` is the raw goal-speed register value (None = fastest).

        With wait=True, returns True once within 2 % of the range of the
        target, or False after 3 s without getting there.
        """
        if not 0 <= angle_deg <= self.range_deg:
            raise ValueError(
                "move_to(%r): outside this servo's range 0..%r degrees (min_raw=%d, max_raw=%d)"
                % (angle_deg, self.range_deg, self.min_raw, self.max_raw)
            )
        estop.check("%s move_to()" % type(self).__name__)
        raw_speed = 0 if speed is None else max(0, min(32767, int(speed)))
        self._write(_scs.REG_TORQUE_ENABLE, b"\x01")
        goal = self._raw_for(angle_deg)
        self._write(
            _scs.REG_GOAL_POSITION, bytes((goal & 0xFF, goal >> 8, 0, 0, raw_speed & 0xFF, raw_speed >> 8))
        )
        if not wait:
            return True
        tolerance = 0.02 * self.range_deg
        deadline = time.ticks_add(time.ticks_ms(), 3000)
        while True:
            here = self.angle()
            if here is not None and abs(here - angle_deg) <= tolerance:
                return True
            if time.ticks_diff(deadline, time.ticks_ms()) <= 0:
                return False
            time.sleep_ms(10)

    def angle(self):
        """Shaft angle in degrees within the range, or None if the servo did not answer."""
        data = self._read(_scs.REG_PRESENT_POSITION, 2)
        if data is None:
            return None
        return (_u16(data, 0) - self.min_raw) * self.range_deg / (self.max_raw - self.min_raw)

    def coast(self):
        """Release the horn (torque off)."""
        self._write(_scs.REG_TORQUE_ENABLE, b"\x00")


class _StepMove:
    """A run_angle in flight: the steps still to issue and how it should end."""

    def __init__(self, counts_left, then, speed_dps, tolerance_counts):
        self.counts_left = counts_left
        self.then = then
        self.speed_dps = speed_dps
        self.tolerance_counts = tolerance_counts
        self.best_remaining = None
        self.best_ms = 0


class ST3215Motor(_BusServo, Motor):
    """One ST-3215 as a wheel (Motor interface): the servo's own loops, multi-turn angle in software.

    Speeds go to the servo's velocity loop (wheel mode); run_angle uses step
    mode, where a goal is a signed relative step, so moves cross full turns
    and go past 7 turns as chained steps. A DriveBase can adopt the motor:
    `bus.hand_over()` gives it the UART and `adopt(port, slot)` routes this
    object's Motor calls through it.

    Odometry: the angle limits are set to 0/0 at construction, which makes
    Present Position a multi-turn count in a +-32767 window (about 8 turns)
    instead of one 12-bit turn. `angle()` unwraps that window using the
    travel it expects from the measured speeds and the servo's own ramp, and
    every speed command folds in a reading first so the ramp starts at a known
    point; a program may run for many seconds between angle() calls without
    losing turns (the window leaves +-4 turns of slack for the estimate).
    """

    #: Datasheet stall torque in mNm: the scale of load().
    STALL_TORQUE_MNM = 2940.0
    #: stalled() needs the load at or above this percent of the stall torque...
    STALL_LOAD_PCT = 80
    #: ...while the shaft turns at most this fast, in deg/s.
    STALL_SPEED_DPS = 20.0

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
        max_dps=600.0,
        accel_dps2=1500.0,
        raise_on_stall=False,
        stall_idle_ms=1000,
    ):
        counts_per_rev = _codec().COUNTS_PER_REV
        if steps_per_dps is None:
            steps_per_dps = counts_per_rev / 360
        if steps_per_dps <= 0 or max_dps <= 0 or accel_dps2 < 0 or stall_idle_ms <= 0:
            raise ValueError(
                "steps_per_dps=%r, max_dps=%r, stall_idle_ms=%r must be > 0 and accel_dps2=%r >= 0"
                % (steps_per_dps, max_dps, stall_idle_ms, accel_dps2)
            )
        self.invert = bool(invert)
        self.steps_per_dps = steps_per_dps
        self.max_dps = max_dps
        self.accel_dps2 = accel_dps2
        self.raise_on_stall = raise_on_stall
        self.stall_idle_ms = stall_idle_ms
        self._port = None  # set by adopt()
        self._move = None
        self._cap_stack = []
        self._cap_pct = 100
        self._sign = -1 if self.invert else 1
        self._counts_per_deg = counts_per_rev / 360
        # Angle tracking, in servo counts (servo frame).
        self._counts = 0.0
        self._offset_deg = 0.0
        self._last_raw = None
        self._last_us = 0
        self._last_cps = 0
        self._cmd_cps = 0  # last commanded wheel speed, servo frame
        self._step_base = 0.0
        self._step_counts = 0
        self._remaining = 0
        self._attach(servo_id, uart_id, tx, rx, baud, dir_pin)
        self._torque = False
        self._write(_scs.REG_TORQUE_ENABLE, b"\x00")
        self._write(_scs.REG_MIN_ANGLE, b"\x00\x00\x00\x00")  # multi-turn: see the class docstring
        self._write(_scs.REG_ACCELERATION, bytes((self._acc_register(),)))
        self._write(_scs.REG_GOAL_SPEED, b"\x00\x00")
        self._mode = None
        self._enter_mode(_scs.MODE_WHEEL)
        estop.on_engage(self.coast)  # torque off: instant, not ramped like brake()

    # --- adoption by a DriveBase -------------------------------------------------

    @classmethod
    def migrate_bus_to_native(cls, bus, skip=()):
        """Move every motor still on `bus` onto native slots; returns the motors moved.

        DriveBase calls this right after it adopts its wheels, which hands the UART to the bus
        engine: anything else sharing the chain (an arm, a spare wheel) has to come across too or
        it is left talking into a closed UART. `skip` lists motors to leave alone (the wheels,
        already adopted). Position-mode servos (no adopt()) stay put and say so when used.
        """
        port = None
        for device in bus.devices:
            port = getattr(device, "_port", None)
            if port is not None:
                break
        if port is None:
            raise RuntimeError(
                "UART%d is not on a bus engine yet: a DriveBase adopts its wheels first, and this "
                "then moves the rest of the chain" % bus.uart_id
            )
        moved = []
        for device in bus.devices:
            if device in skip or not hasattr(device, "adopt") or port.slot_of(device) is not None:
                continue
            port.adopt(device)
            moved.append(device)
        return moved

    def adopt(self, port, slot):
        """Route this motor's Motor calls through `port` (the owner of the UART now), as `slot`.

        `port` provides run_speed, dc, brake, coast, hold, angle, reset_angle,
        speed, load, stalled, run_angle and done, each taking the slot first and
        working in this motor's user frame (invert applied), plus
        `set_duty_limit(slot, pct)`. Pass port=None to take the motor back.
        """
        self._move = None
        self._port = port
        self.slot = slot

    # --- register plumbing ---------------------------------------------------------

    def _acc_register(self):
        if self.accel_dps2 <= 0:
            return 0  # the servo's "no ramp": instant speed changes
        return max(1, min(254, int(round(self.accel_dps2 * self.steps_per_dps / 100))))

    def _encode_goal_speed(self, deg_per_s):
        """The goal-speed register bytes for `deg_per_s` in the user frame (clamped, inverted)."""
        deg_per_s = max(-self.max_dps, min(self.max_dps, deg_per_s)) * self._sign
        raw = _sign_magnitude(deg_per_s * self.steps_per_dps, _scs.SPEED_SIGN_BIT)
        return bytes((raw & 0xFF, raw >> 8))

    def _speed_command(self, deg_per_s):
        """Goal-speed bytes for a new wheel speed, after folding in the motion under the old one."""
        self._feedback()
        data = self._encode_goal_speed(deg_per_s)
        self._cmd_cps = _from_sign_magnitude(_u16(data, 0), _scs.SPEED_SIGN_BIT)
        return data

    def _set_torque(self, on):
        if self._torque != on:
            self._write(_scs.REG_TORQUE_ENABLE, b"\x01" if on else b"\x00")
            self._torque = on

    def _enter_mode(self, mode):
        """Switch the servo's operating mode, keeping the angle accumulator continuous across it."""
        if self._mode == mode:
            return
        self._checked_feedback()  # fold in motion up to the switch (in step mode: the steps travelled)
        self._write(_scs.REG_MODE, bytes((mode,)))
        self._mode = mode
        if mode == _scs.MODE_STEP:
            self._step_base = self._counts
            self._step_counts = 0
            self._remaining = 0
        else:
            self._last_raw = None
            self._checked_feedback()  # baseline for the wrap tracking in the new mode

    def _expected_counts(self, dt_s, end_cps):
        """How far the shaft should have turned since the last reading, from what is known about it."""
        start_cps = self._last_cps
        if not self._torque:
            # Free-wheeling through a 1:205-ish gearbox stops within a fraction of a second.
            return (start_cps + end_cps) * 0.5 * min(dt_s, 0.5)
        accel = self._acc_register() * 100
        if (
            self._mode == _scs.MODE_WHEEL
            and accel
            and abs(end_cps - self._cmd_cps) <= 0.05 * abs(self._cmd_cps) + 20
        ):
            # Reached the commanded speed: ramp from the last reading, then cruise.
            ramp_s = abs(self._cmd_cps - start_cps) / accel
            if ramp_s < dt_s:
                return (start_cps + self._cmd_cps) * 0.5 * ramp_s + self._cmd_cps * (dt_s - ramp_s)
        return (start_cps + end_cps) * 0.5 * dt_s

    def _feedback(self):
        """Read position, speed and load in one transaction; (speed in counts/s, load in 0.1 %) or None."""
        data = self._read(_scs.REG_PRESENT_POSITION, 6)
        if data is None:
            return None
        raw = _u16(data, 0)
        cps = _from_sign_magnitude(_u16(data, 2), _scs.SPEED_SIGN_BIT)
        load = _from_sign_magnitude(_u16(data, 4), _scs.LOAD_SIGN_BIT)
        now = time.ticks_us()
        if self._mode == _scs.MODE_STEP:
            self._remaining = _from_sign_magnitude(raw, _scs.POSITION_SIGN_BIT)
            self._counts = self._step_base + self._step_counts - self._remaining
        else:
            value = _from_sign_magnitude(raw, _scs.POSITION_SIGN_BIT)
            if self._last_raw is not None:
                delta = value - self._last_raw
                expected = self._expected_counts(time.ticks_diff(now, self._last_us) / 1e6, cps)
                delta += round((expected - delta) / _scs.MULTI_TURN_SPAN) * _scs.MULTI_TURN_SPAN
                self._counts += delta
            self._last_raw = value
        self._last_us = now
        self._last_cps = cps
        return cps, load

    def _checked_feedback(self):
        reading = self._feedback()
        if reading is None:
            raise self._silent()
        return reading

    # --- Motor ---------------------------------------------------------------------

    def angle(self):
        """Shaft angle in degrees, multi-turn, in the reset_angle() frame; None if the servo is silent."""
        if self._port is not None:
            return self._port.angle(self.slot)
        if self._feedback() is None:
            return None
        return self._sign * self._counts / self._counts_per_deg + self._offset_deg

    def reset_angle(self, angle=0):
        if self._port is not None:
            return self._port.reset_angle(self.slot, angle)
        self._checked_feedback()
        self._offset_deg = angle - self._sign * self._counts / self._counts_per_deg

    def speed(self):
        """Measured shaft speed in deg/s from the present-speed register; None if the servo is silent."""
        if self._port is not None:
            return self._port.speed(self.slot)
        reading = self._feedback()
        if reading is None:
            return None
        return self._sign * reading[0] / self.steps_per_dps

    def load(self):
        """Estimated shaft torque in mNm (load register x datasheet stall torque); None if silent."""
        if self._port is not None:
            return self._port.load(self.slot)
        reading = self._feedback()
        if reading is None:
            return None
        return self._sign * reading[1] / 1000 * self.STALL_TORQUE_MNM

    def stalled(self):
        """True while the servo pushes at >= STALL_LOAD_PCT of its torque cap yet turns <= STALL_SPEED_DPS.

        A silent servo raises: "no answer" must never read as "not stalled".
        """
        if self._port is not None:
            return self._port.stalled(self.slot)
        cps, load = self._checked_feedback()
        pushing = abs(load) >= self.STALL_LOAD_PCT * self._cap_pct / 10
        return pushing and abs(cps) / self.steps_per_dps <= self.STALL_SPEED_DPS

    def run_speed(self, deg_per_s):
        """Spin at `deg_per_s` (clamped to max_dps) on the servo's velocity loop, ramped at accel_dps2."""
        if self._port is not None:
            return self._port.run_speed(self.slot, deg_per_s)  # the port refuses during an e-stop
        estop.check("%s run_speed()" % type(self).__name__)
        self._wheel_speed(deg_per_s)

    def _wheel_speed(self, deg_per_s):
        self._move = None
        self._write(_scs.REG_GOAL_SPEED, self._speed_command(deg_per_s))
        self._prepare_wheel()

    def _prepare_wheel(self):
        self._enter_mode(_scs.MODE_WHEEL)
        self._set_torque(True)

    def brake(self):
        """Ramp to zero speed at accel_dps2 and hold zero rate (torque stays on)."""
        if self._port is not None:
            return self._port.brake(self.slot)
        self._wheel_speed(0)  # a stop, so allowed while the e-stop is engaged

    def coast(self):
        """Torque off: the shaft free-wheels. Instant (not ramped)."""
        if self._port is not None:
            return self._port.coast(self.slot)
        self._move = None
        self._set_torque(False)
        if self._mode != _scs.MODE_WHEEL:
            # Step-mode position reads are "steps to go" and mean nothing while free-wheeling.
            self._enter_mode(_scs.MODE_WHEEL)

    def hold(self):
        """Hold the current shaft angle on the servo's position loop."""
        if self._port is not None:
            return self._port.hold(self.slot)
        self._move = None
        # A zero step in step mode: the servo's position loop keeps the shaft where it is, and
        # the multi-turn odometry carries on from the steps-to-go reading.
        self._enter_mode(_scs.MODE_STEP)
        self._set_torque(True)
        self._checked_feedback()
        self._step_base = self._counts
        self._step_counts = 0
        self._write(_scs.REG_GOAL_POSITION, b"\x00\x00", attempts=1)

    def dc(self, duty):
        """Raw duty -100..100 on the servo's open-loop mode: no speed regulation, speed sags with load."""
        if self._port is not None:
            return self._port.dc(self.slot, duty)
        estop.check("%s dc()" % type(self).__name__)
        self._move = None
        duty = max(-100, min(100, duty)) * self._sign
        raw = _sign_magnitude(duty * 10, _scs.DUTY_SIGN_BIT)
        self._write(_scs.REG_GOAL_TIME, bytes((raw & 0xFF, raw >> 8)))
        self._enter_mode(_scs.MODE_DUTY)
        self._set_torque(True)

    def _duty_limit_push(self, limit_pct):
        if self._port is not None:
            self._port.set_duty_limit(self.slot, limit_pct)
        else:
            raw = int(round(limit_pct * 10))
            self._write(_scs.REG_TORQUE_LIMIT, bytes((raw & 0xFF, raw >> 8)))
        self._cap_stack.append(self._cap_pct)
        self._cap_pct = limit_pct

    def _duty_limit_pop(self):
        self._cap_pct = self._cap_stack.pop()
        if self._port is not None:
            self._port.set_duty_limit(self.slot, self._cap_pct)
            return
        raw = int(round(self._cap_pct * 10))
        self._write(_scs.REG_TORQUE_LIMIT, bytes((raw & 0xFF, raw >> 8)))

    def run_angle(
        self,
        deg_per_s,
        target_angle,
        wait=True,
        tolerance_deg=0.5,
        kp=None,
        poll_ms=None,
        debug=False,
        then=Stop.COAST,
    ):
        """Rotate by `target_angle` degrees (relative, any size, sign = direction) at up to `deg_per_s`.

        Runs in step mode: each goal is a signed relative step of at most 7
        turns, so moves cross the 0/4095 seam and longer moves are chained, each
        step parking before the next. With wait=False, poll done(): it issues
        the next step and applies `then` at the end. `kp`, `poll_ms` and `debug`
        are accepted for older programs; the loop runs on the servo.
        """
        name = then_name(then)
        if self._port is not None:
            return self._port.run_angle(self.slot, deg_per_s, target_angle, wait, name)
        estop.check("%s run_angle()" % type(self).__name__)
        speed_dps = min(abs(deg_per_s), self.max_dps)
        if speed_dps == 0:
            raise ValueError("run_angle(deg_per_s=0): the move would never finish; give a non-zero speed")
        self._move = None
        self._enter_mode(_scs.MODE_STEP)
        raw = _sign_magnitude(speed_dps * self.steps_per_dps, _scs.SPEED_SIGN_BIT)  # a magnitude in step mode
        self._write(_scs.REG_GOAL_SPEED, bytes((raw & 0xFF, raw >> 8)))
        self._set_torque(True)
        counts = int(round(target_angle * self._counts_per_deg)) * self._sign
        tolerance = max(1, int(tolerance_deg * self._counts_per_deg))
        direction = 1 if target_angle >= 0 else -1
        self._move = _StepMove(counts, name, speed_dps * direction, tolerance)
        self._issue_step()
        if wait:
            pause_ms = poll_ms or 5
            while not self.done():
                time.sleep_ms(pause_ms)

    def _issue_step(self):
        move = self._move
        longest = _MAX_STEP_TURNS * _scs.COUNTS_PER_REV
        step = max(-longest, min(longest, move.counts_left))
        move.counts_left -= step
        self._step_base = self._counts
        self._step_counts = step
        self._remaining = step
        move.best_remaining = abs(step)
        move.best_ms = time.ticks_ms()
        raw = _sign_magnitude(step, _scs.POSITION_SIGN_BIT)
        # Never retried: a relative step whose acknowledgement got lost may already be running.
        self._write(_scs.REG_GOAL_POSITION, bytes((raw & 0xFF, raw >> 8)), attempts=1)

    def done(self):
        """True when no run_angle(wait=False) move is in flight; polling it advances a chained move."""
        if self._port is not None:
            return self._port.done(self.slot)
        move = self._move
        if move is None:
            return True
        cps = self._checked_feedback()[0]
        remaining = abs(self._remaining)
        if remaining <= move.tolerance_counts and abs(cps) <= _PARKED_CPS:
            if move.counts_left:
                # The next step is relative to where this one parked, so it carries the leftover.
                move.counts_left += self._remaining
                self._issue_step()
                return False
            self._move = None
            if move.then == Stop.NONE:
                self._wheel_speed(move.speed_dps)
            elif move.then != Stop.HOLD:  # step mode is already holding the target
                self._finish(move.then)
            return True
        now = time.ticks_ms()
        if remaining < move.best_remaining - move.tolerance_counts:
            move.best_remaining = remaining
            move.best_ms = now
        elif time.ticks_diff(now, move.best_ms) >= self.stall_idle_ms:
            return self._stalled_move(move)
        return False

    def _stalled_move(self, move):
        self._move = None
        short_deg = (move.counts_left + self._remaining) / self._counts_per_deg
        if self.raise_on_stall:
            self.coast()
            raise RuntimeError(
                "%s (servo id %d) stalled in run_angle: no progress for %d ms, %.1f degrees short of the "
                "target; the shaft is blocked or the load is beyond the servo's torque"
                % (self.side or type(self).__name__, self.servo_id, self.stall_idle_ms, abs(short_deg))
            )
        self._finish(move.then if move.then != Stop.NONE else Stop.HOLD)
        return True


class SyncServoGroup:
    """Goal speeds for several wheel-mode servos in one SYNC WRITE, so they change at one packet boundary.

    For arms and grippers; drivebase wheels go through DriveBase.move_wheels().
    """

    def __init__(self, servos):
        servos = list(servos)
        if not servos:
            raise ValueError("SyncServoGroup needs at least one servo")
        bus = servos[0].bus
        for servo in servos:
            if servo.bus is not bus:
                raise ValueError(
                    "servo id %d is on %s but the group's first servo is on %s; "
                    "a SYNC WRITE reaches one bus only" % (servo.servo_id, servo.bus.where(), bus.where())
                )
        self.servos = servos
        self.bus = bus

    def set_goal_speeds(self, speeds_dps):
        """Write each servo's goal speed (its own invert / steps_per_dps / max_dps applied) in one packet."""
        if len(speeds_dps) != len(self.servos):
            raise ValueError("%d speeds for %d servos" % (len(speeds_dps), len(self.servos)))
        estop.check("SyncServoGroup.set_goal_speeds()")
        items = []
        for i, servo in enumerate(self.servos):
            if not hasattr(servo, "_encode_goal_speed"):
                raise TypeError(
                    "servo id %d is a %s (position mode); goal speeds need wheel-mode motors such as "
                    "ST3215Motor" % (servo.servo_id, type(servo).__name__)
                )
            items.append((servo.servo_id, servo._speed_command(speeds_dps[i])))
        # Speeds first: servos already spinning change at this packet; any that still have to
        # be switched into wheel mode start on the new speed rather than a stale one.
        self.bus.sync_write(_scs.REG_GOAL_SPEED, 2, items)
        for servo in self.servos:
            servo._move = None
            servo._prepare_wheel()
