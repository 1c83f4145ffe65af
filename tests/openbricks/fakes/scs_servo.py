"""Fake Feetech ST-3215 / ST-3032 servos on a fake half-duplex UART, at the register level.

    bus = ScsBus()
    left = bus.add(FakeServo(1))
    machine.board.attach_uart(1, bus)

`ScsBus.handle()` parses the SCS packets the driver writes (PING, READ, WRITE,
SYNC WRITE, broadcast) and answers from each servo's
register file with correct checksums and status error flags. Each servo has a
shaft that the virtual clock advances: wheel mode (1) tracks goal speed under
the acceleration register, position mode (0) runs a trapezoid to a goal inside
one turn (never across the 0/4095 seam, as the real single-turn mode does),
open-loop mode (2) spins at a duty share of no-load speed, and step mode (3)
moves by a signed relative step while Present Position reads the steps still
to go. Tests can silence a servo, change its id, block its shaft or put a wall
in its way, and read back every register and the true shaft angle.
"""

import math

from . import bounded, clock

INST_PING = 0x01
INST_READ = 0x02
INST_WRITE = 0x03
INST_SYNC_WRITE = 0x83
BROADCAST_ID = 0xFE

# Register addresses (STS series memory map).
REG_ID = 0x05
REG_RESPONSE_LEVEL = 0x08
REG_MIN_ANGLE = 0x09
REG_MAX_ANGLE = 0x0B
REG_MAX_TORQUE = 0x10
REG_MODE = 0x21
REG_TORQUE_ENABLE = 0x28
REG_ACC = 0x29
REG_GOAL_POSITION = 0x2A
REG_GOAL_TIME = 0x2C  # holds the signed duty in open-loop mode 2
REG_GOAL_SPEED = 0x2E
REG_TORQUE_LIMIT = 0x30
REG_LOCK = 0x37
REG_PRESENT_POSITION = 0x38
REG_PRESENT_SPEED = 0x3A
REG_PRESENT_LOAD = 0x3C
REG_PRESENT_VOLTAGE = 0x3E
REG_PRESENT_TEMPERATURE = 0x3F
REG_MOVING = 0x42
REG_PRESENT_CURRENT = 0x45
_REG_COUNT = 0x50

# Status-byte error flags.
ERR_VOLTAGE = 0x01
ERR_SENSOR = 0x02
ERR_TEMPERATURE = 0x04
ERR_CURRENT = 0x08
ERR_ANGLE = 0x10
ERR_OVERLOAD = 0x20

COUNTS_PER_REV = 4096
_STEP_US = 1000  # shaft integration step
_FREEWHEEL_TAU_S = 0.03  # a coasting shaft behind a ~1:200 gearbox stops almost at once
_DUTY_TAU_S = 0.05  # open-loop speed response to a duty step
_OVERLOAD_LOAD = 800  # 0.1 % units: the datasheet's "> 80 % of stall ..."
_OVERLOAD_US = 2_000_000  # "... for 2 s" unloads the torque and flags overload


def checksum(body):
    return (~sum(body)) & 0xFF


def packet(servo_id, instr_or_status, params=b""):
    body = bytes([servo_id, len(params) + 2, instr_or_status]) + bytes(params)
    return b"\xff\xff" + body + bytes([checksum(body)])


def sign_magnitude(value, sign_bit):
    value = int(round(value))
    if value < 0:
        return min(-value, (1 << sign_bit) - 1) | (1 << sign_bit)
    return min(value, (1 << sign_bit) - 1)


def from_sign_magnitude(raw, sign_bit):
    magnitude = raw & ((1 << sign_bit) - 1)
    return -magnitude if raw & (1 << sign_bit) else magnitude


class FakeServo:
    """One servo: a register file and a shaft. Angles and speeds are in encoder counts."""

    def __init__(self, servo_id, no_load_dps=888.0):
        self.regs = bytearray(_REG_COUNT)
        self.regs[REG_ID] = servo_id
        self.regs[REG_RESPONSE_LEVEL] = 1
        self._put16(REG_MIN_ANGLE, 0)
        self._put16(REG_MAX_ANGLE, 4095)
        self._put16(REG_MAX_TORQUE, 1000)
        self._put16(REG_TORQUE_LIMIT, 1000)
        self.regs[REG_PRESENT_VOLTAGE] = 120
        self.regs[REG_PRESENT_TEMPERATURE] = 31
        self.max_cps = no_load_dps * COUNTS_PER_REV / 360.0
        self.position = 0.0  # true shaft position, counts, unbounded
        self.velocity = 0.0  # counts/s
        self.target = 0.0  # position-mode / step-mode destination
        self.load = 0.0  # 0.1 % of stall, signed
        self.silent = False
        self.blocked = False
        self.wall = None  # (position counts, side): the shaft cannot pass it
        self.error_flags = 0
        self.writes = []  # (address, bytes) of every write it accepted, in order
        self._pushing_us = 0
        self._last_us = clock.now_us()

    # --- test handles ---------------------------------------------------------

    @property
    def servo_id(self):
        return self.regs[REG_ID]

    @property
    def mode(self):
        return self.regs[REG_MODE]

    @property
    def torque_enabled(self):
        self.advance()  # overload protection may have unloaded it since the last access
        return self._torque_on()

    def _torque_on(self):
        return self.regs[REG_TORQUE_ENABLE] == 1

    def angle_deg(self):
        self.advance()
        return self.position * 360.0 / COUNTS_PER_REV

    def speed_dps(self):
        self.advance()
        return self.velocity * 360.0 / COUNTS_PER_REV

    def turn_shaft(self, degrees):
        """Turn the output by hand (e.g. while it coasts)."""
        self.advance()
        self.position += degrees * COUNTS_PER_REV / 360.0

    def block(self):
        """Jam the shaft where it is: it can still push, but not move."""
        self.advance()
        self.blocked = True

    def unblock(self):
        self.advance()
        self.blocked = False
        self.wall = None

    def put_wall(self, angle_deg):
        """An end stop at `angle_deg` (true shaft frame) on the side the shaft now faces it from."""
        self.advance()
        at = angle_deg * COUNTS_PER_REV / 360.0
        self.wall = (at, 1 if at >= self.position else -1)

    def reg16(self, address):
        self.advance()
        self._refresh()
        return self.regs[address] | (self.regs[address + 1] << 8)

    # --- shaft ------------------------------------------------------------------

    def _get16(self, address):
        return self.regs[address] | (self.regs[address + 1] << 8)

    def _put16(self, address, value):
        self.regs[address] = value & 0xFF
        self.regs[address + 1] = (value >> 8) & 0xFF

    def _accel_cps2(self):
        acc = self.regs[REG_ACC]
        return acc * 100.0 if acc else 1e9  # 0 means "as fast as the motor can"

    def _speed_cap_cps(self):
        goal = abs(from_sign_magnitude(self._get16(REG_GOAL_SPEED), 15))
        return min(goal, self.max_cps) if goal else self.max_cps

    def _multi_turn(self):
        return self._get16(REG_MIN_ANGLE) == 0 and self._get16(REG_MAX_ANGLE) == 0

    def advance(self):
        now = clock.now_us()
        while self._last_us < now:
            step_us = min(_STEP_US, now - self._last_us)
            self._step(step_us / 1e6)
            self._last_us += step_us

    def _ramp(self, wanted, dt):
        dv = self._accel_cps2() * dt
        if abs(wanted - self.velocity) <= dv:
            return wanted
        return self.velocity + (dv if wanted > self.velocity else -dv)

    def _step(self, dt):
        mode = self.mode
        effort = 0.0  # sign of the push the servo is making, for the load model
        if not self._torque_on():
            self.target = self.position  # the firmware keeps the goal at present while unloaded
            self.velocity *= math.exp(-dt / _FREEWHEEL_TAU_S)
            if abs(self.velocity) < 1.0:
                self.velocity = 0.0
        elif mode == 1:
            goal = from_sign_magnitude(self._get16(REG_GOAL_SPEED), 15)
            goal = max(-self.max_cps, min(self.max_cps, goal))
            self.velocity = self._ramp(goal, dt)
            effort = goal
        elif mode == 2:
            duty = from_sign_magnitude(self._get16(REG_GOAL_TIME), 10) / 1000.0
            wanted = duty * self.max_cps
            self.velocity += (wanted - self.velocity) * min(1.0, dt / _DUTY_TAU_S)
            effort = duty
        else:
            error = self.target - self.position
            if abs(error) < 0.5 and abs(self.velocity) < self._accel_cps2() * dt + 1:
                self.position = self.target
                self.velocity = 0.0
            else:
                cap = self._speed_cap_cps()
                wanted = math.sqrt(2.0 * self._accel_cps2() * max(0.0, abs(error) - 0.5))
                wanted = min(cap, wanted)
                wanted = wanted if error > 0 else -wanted
                self.velocity = self._ramp(wanted, dt)
                # Land exactly rather than hop over the target inside one step.
                if (self.velocity > 0 and self.position + self.velocity * dt > self.target) or (
                    self.velocity < 0 and self.position + self.velocity * dt < self.target
                ):
                    self.velocity = (self.target - self.position) / dt
                effort = error
        moved = self.velocity * dt
        stopped_by = self._obstacle(moved)
        if stopped_by is not None:
            self.position = stopped_by
            self.velocity = 0.0
        else:
            self.position += moved
        self._update_load(effort, effort != 0 and stopped_by is not None, dt)

    def _obstacle(self, moved):
        if self.blocked:
            return self.position
        if self.wall is not None:
            at, side = self.wall
            if side > 0 and self.position + moved >= at:
                return at
            if side < 0 and self.position + moved <= at:
                return at
        return None

    def _update_load(self, effort, pushing_against_something, dt):
        limit = min(self._get16(REG_TORQUE_LIMIT), self._get16(REG_MAX_TORQUE))
        if not self._torque_on() or (effort == 0 and self.velocity == 0):
            self.load = 0.0
            self._pushing_us = 0
            return
        if pushing_against_something:
            self.load = limit if effort > 0 else -limit
            if self.load and abs(self.load) >= _OVERLOAD_LOAD:
                self._pushing_us += int(dt * 1e6)
                if self._pushing_us >= _OVERLOAD_US:
                    self.error_flags |= ERR_OVERLOAD
                    self.regs[REG_TORQUE_ENABLE] = 0
            return
        self._pushing_us = 0
        share = 30 + 150 * abs(self.velocity) / self.max_cps  # friction grows with speed
        direction = self.velocity if self.velocity else effort
        self.load = min(share, limit) if direction >= 0 else -min(share, limit)

    def _refresh(self):
        """Write the shaft's state into the read-only registers."""
        mode = self.mode
        if mode == 3:
            present = sign_magnitude(self.target - self.position, 15)
        elif self._multi_turn():
            # The 16-bit sign-magnitude window holds +-32767 counts (about 8 turns) and wraps.
            counts = int(round(self.position))
            present = sign_magnitude(((counts + 32767) % 65535) - 32767, 15)
        else:
            present = int(round(self.position)) % COUNTS_PER_REV
        self._put16(REG_PRESENT_POSITION, present)
        self._put16(REG_PRESENT_SPEED, sign_magnitude(self.velocity, 15))
        self._put16(REG_PRESENT_LOAD, sign_magnitude(self.load, 10))
        self._put16(REG_PRESENT_CURRENT, sign_magnitude(abs(self.load) * 1.6, 15))
        self.regs[REG_MOVING] = 1 if abs(self.velocity) > 0 else 0

    # --- the wire side -------------------------------------------------------------

    def write(self, address, data):
        """Apply a register write the way the servo firmware does."""
        self.advance()
        bounded.append(self.writes, (address, bytes(data)))
        for i, byte in enumerate(data):
            if address + i < _REG_COUNT:
                self.regs[address + i] = byte
        end = address + len(data)
        if address <= REG_TORQUE_ENABLE < end and self.regs[REG_TORQUE_ENABLE]:
            self.error_flags &= ~ERR_OVERLOAD
            self._pushing_us = 0
        if address <= REG_GOAL_POSITION < end:
            goal = self._get16(REG_GOAL_POSITION)
            if self.mode == 3:
                self.target = self.position + from_sign_magnitude(goal, 15)
            elif self._multi_turn():
                self.target = from_sign_magnitude(goal, 15)
            else:
                low = self._get16(REG_MIN_ANGLE)
                high = self._get16(REG_MAX_ANGLE)
                goal = max(low, min(high, goal))
                here = self.position % COUNTS_PER_REV
                self.target = self.position + (goal - here)
        if address <= REG_MODE < end:
            self.target = self.position  # a fresh mode starts from where the shaft is

    def read(self, address, length):
        self.advance()
        self._refresh()
        return bytes(self.regs[address : address + length])

    def reply(self, params=b""):
        return packet(self.servo_id, self.error_flags, params)


class ScsBus:
    """The daisy chain: every servo sees every packet; the addressed one answers."""

    def __init__(self):
        self.servos = {}
        self.packets = []  # every well-formed packet seen: (id, instruction, params)
        self.garbage = 0  # bytes that were not part of a valid packet

    def add(self, servo):
        self.servos[servo.servo_id] = servo
        return servo

    def servo(self, servo_id):
        return self.servos[servo_id]

    def change_id(self, old_id, new_id):
        servo = self.servos.pop(old_id)
        servo.regs[REG_ID] = new_id
        self.servos[new_id] = servo

    def _packets(self, data):
        i = 0
        while i + 6 <= len(data):
            if data[i] != 0xFF or data[i + 1] != 0xFF:
                self.garbage += 1
                i += 1
                continue
            length = data[i + 3]
            end = i + 4 + length
            if length < 2 or end > len(data):
                self.garbage += len(data) - i
                return
            body = data[i + 2 : end - 1]
            if checksum(body) != data[end - 1]:
                self.garbage += end - i
                i = end
                continue
            yield body[0], body[2], bytes(body[3:])
            i = end
        self.garbage += len(data) - i

    def handle(self, data):
        out = b""
        for servo_id, instr, params in self._packets(bytes(data)):
            bounded.append(self.packets, (servo_id, instr, params))
            if instr == INST_SYNC_WRITE:
                self._sync_write(params)
                continue
            if servo_id == BROADCAST_ID:
                for servo in list(self.servos.values()):
                    self._execute(servo, instr, params)
                continue
            servo = self.servos.get(servo_id)
            if servo is None:
                continue
            answer = self._execute(servo, instr, params)
            if answer is not None:
                out += answer
        return out

    def _sync_write(self, params):
        address, width = params[0], params[1]
        body = params[2:]
        for i in range(0, len(body) - width, width + 1):
            servo = self.servos.get(body[i])
            if servo is not None and not servo.silent:
                servo.write(address, body[i + 1 : i + 1 + width])

    def _execute(self, servo, instr, params):
        if servo.silent:
            return None
        acknowledge = servo.regs[REG_RESPONSE_LEVEL] >= 1
        if instr == INST_PING:
            return servo.reply()
        if instr == INST_READ:
            return servo.reply(servo.read(params[0], params[1]))
        if instr == INST_WRITE:
            old_id = servo.servo_id
            servo.write(params[0], params[1:])
            if servo.servo_id != old_id and self.servos.get(old_id) is servo:
                del self.servos[old_id]
                self.servos[servo.servo_id] = servo
            return servo.reply() if acknowledge else None
        return None
