"""The serial bus in the simulator: emulated ST-3032 servos on machine.UART, and the adoption engine.

`ServoBus` is what the shim's UART delivers bytes to. It parses SCS packets
with the firmware's own codec (openbricks_native.scs) and answers from each
servo's register file, so the unchanged ST3032Motor driver code path runs:
ping, register reads and writes, SYNC WRITE, broadcast.

`ServoFirmware` is one servo's firmware as the bus sees it: the register file
(the map is the codec's, scs.REG_*) and what a write does to it. What turns
the shaft is a subclass's: `EmulatedServo` below, or the kinematic shaft the
runtime's tests put on their virtual clock (tests/openbricks/fakes/scs_servo.py),
which also run this module on MicroPython's unix port (imported as `serial_bus`
with `sim/` on the path).

Each `EmulatedServo` is a servo's firmware over one simulated wheel: a native
`openbricks_native.Servo` on a native wheel IO in the servo's own shaft frame
(a right-hand servo is mounted mirrored, so its shaft frame is the wheel's
negated). Its loop runs on the world's MotorProcess, ticked inside the
physics step: wheel mode runs the speed loop at the acceleration register's
ramp, mode 2 is open-loop duty, mode 3 moves by relative steps and holds,
position mode moves to a goal. No Python runs per millisecond.

`BusEngine` is what `_openbricks_native.serial_bus(uart_id)` returns in the
simulator: the firmware's own C engine (`openbricks_native.SerialBus`) over
the emulated wire of the adopted servos (`openbricks_mjcontrol.ServoWire`),
with the byte timing of a 1 Mbaud half-duplex line. Adopting a servo moves it
from the Python register emulation onto that wire (its own loop stands down,
as a real servo's does in duty mode); from then on every millisecond the
engine sync-writes duties and reads positions in SCS packets, inside the
physics step, with no Python call.

Register units (STS memory map): position in encoder steps (4096 per turn),
speed in steps/s, acceleration in 100 steps/s^2, load and torque limit in
0.1 % of stall.
"""

try:
    import openbricks_native as native
except ImportError:  # MicroPython with the cores compiled in (the runtime's tests on the unix port)
    import _openbricks_native as native

scs = native.scs

STEPS_PER_REV = scs.COUNTS_PER_REV
_DEG_PER_STEP = 360.0 / STEPS_PER_REV

# "As fast as the motor can" when the acceleration register is 0.
_UNLIMITED_ACCEL_DPS2 = 1.0e6
# Present Moving reads 1 above this shaft speed.
_MOVING_STEPS_PER_S = 10


def sign_magnitude(value, sign_bit):
    """`value` as a register holds it: the magnitude (saturated) below `sign_bit`, the sign at it."""
    value = int(round(value))
    limit = (1 << sign_bit) - 1
    return min(-value, limit) | (1 << sign_bit) if value < 0 else min(value, limit)


def from_sign_magnitude(raw, sign_bit):
    magnitude = raw & ((1 << sign_bit) - 1)
    return -magnitude if raw & (1 << sign_bit) else magnitude


class ServoFirmware:
    """An ST-3032 / ST-3215's firmware as the bus sees it: its register file and what writes do to it.

    A subclass owns the shaft: `advance()` brings it up to now, `shaft_steps()`, `speed_steps()`
    and `load()` (0.1 % of stall, signed) read it, and `written(touched)` acts on a write. Goals are
    decoded here: `target_steps` is where position and step modes head for, in unbounded shaft steps.
    """

    def __init__(self, servo_id):
        self.regs = bytearray(scs.REG_COUNT)
        self.regs[scs.REG_ID] = servo_id
        self.regs[scs.REG_RESPONSE_LEVEL] = 1
        self._put16(scs.REG_MAX_ANGLE, 4095)
        self._put16(scs.REG_MAX_TORQUE, 1000)
        self._put16(scs.REG_TORQUE_LIMIT, 1000)
        self.regs[scs.REG_MODE] = scs.MODE_POSITION
        self.regs[scs.REG_PRESENT_VOLTAGE] = 120
        self.regs[scs.REG_PRESENT_TEMPERATURE] = 31
        self.silent = False  # unplugged: answers nothing
        self.error_flags = 0  # the status byte of every reply (scs.FLAG_*)
        self.target_steps = 0.0

    # --- the shaft (a subclass's) ----------------------------------------------------------

    def advance(self):
        """Bring the shaft up to the present (a no-op where something else moves it)."""

    def shaft_steps(self):
        raise NotImplementedError

    def speed_steps(self):
        raise NotImplementedError

    def load(self):
        raise NotImplementedError

    def written(self, touched):
        """Act on a register write; `touched(register, width=1)` says whether it covered `register`."""

    # --- registers -------------------------------------------------------------------------

    @property
    def servo_id(self):
        return self.regs[scs.REG_ID]

    @property
    def mode(self):
        return self.regs[scs.REG_MODE]

    @property
    def torque_enabled(self):
        return self.regs[scs.REG_TORQUE_ENABLE] == 1

    def _get16(self, address):
        return self.regs[address] | (self.regs[address + 1] << 8)

    def _put16(self, address, value):
        self.regs[address] = value & 0xFF
        self.regs[address + 1] = (value >> 8) & 0xFF

    def reg16(self, address):
        """A 16-bit register as a READ would return it now."""
        self.advance()
        self.refresh()
        return self._get16(address)

    def multi_turn(self):
        return self._get16(scs.REG_MIN_ANGLE) == 0 and self._get16(scs.REG_MAX_ANGLE) == 0

    def goal_speed_steps(self):
        """The goal speed register, signed, steps/s."""
        return from_sign_magnitude(self._get16(scs.REG_GOAL_SPEED), scs.SPEED_SIGN_BIT)

    def duty_pct(self):
        """The open-loop duty of mode 2 (the goal time register), signed, percent."""
        return from_sign_magnitude(self._get16(scs.REG_GOAL_TIME), scs.DUTY_SIGN_BIT) / 10

    def accel_steps2(self):
        """The acceleration register in steps/s^2, or None for "as fast as the motor can" (0)."""
        acc = self.regs[scs.REG_ACCELERATION]
        return acc * 100 if acc else None

    def refresh(self):
        """Write the shaft's state into the read-only registers."""
        steps = self.shaft_steps()
        if self.mode == scs.MODE_STEP:
            present = sign_magnitude(self.target_steps - steps, scs.POSITION_SIGN_BIT)
        elif self.multi_turn():
            half = scs.MULTI_TURN_SPAN // 2
            window = ((int(round(steps)) + half) % scs.MULTI_TURN_SPAN) - half
            present = sign_magnitude(window, scs.POSITION_SIGN_BIT)
        else:
            present = int(round(steps)) % STEPS_PER_REV
        speed = self.speed_steps()
        load = self.load()
        self._put16(scs.REG_PRESENT_POSITION, present)
        self._put16(scs.REG_PRESENT_SPEED, sign_magnitude(speed, scs.SPEED_SIGN_BIT))
        self._put16(scs.REG_PRESENT_LOAD, sign_magnitude(load, scs.LOAD_SIGN_BIT))
        self._put16(scs.REG_PRESENT_CURRENT, sign_magnitude(abs(load) * 1.6, 15))
        self.regs[scs.REG_MOVING] = 1 if abs(speed) > _MOVING_STEPS_PER_S else 0

    def read(self, address, length):
        self.advance()
        self.refresh()
        return bytes(self.regs[address : address + length])

    def write(self, address, data):
        """Apply a register write the way the servo firmware does."""
        self.advance()
        end = address + len(data)
        for i, byte in enumerate(data):
            if address + i < scs.REG_COUNT:
                self.regs[address + i] = byte

        def touched(register, width=1):
            return address < register + width and register < end

        if touched(scs.REG_MODE):
            self.target_steps = self.shaft_steps()  # a fresh mode starts from where the shaft is
        if touched(scs.REG_GOAL_POSITION, 2):
            goal = self._get16(scs.REG_GOAL_POSITION)
            here = self.shaft_steps()
            if self.mode == scs.MODE_STEP:
                self.target_steps = here + from_sign_magnitude(goal, scs.POSITION_SIGN_BIT)
            elif self.multi_turn():
                self.target_steps = from_sign_magnitude(goal, scs.POSITION_SIGN_BIT)
            else:
                low, high = self._get16(scs.REG_MIN_ANGLE), self._get16(scs.REG_MAX_ANGLE)
                goal = max(low, min(high, goal))
                self.target_steps = here + (goal - here % STEPS_PER_REV)
        self.written(touched)

    def reply(self, params=b""):
        return scs.status(self.servo_id, self.error_flags, params)


class EmulatedServo(ServoFirmware):
    """One ST-3032's firmware over a simulated wheel, its loops run natively."""

    def __init__(self, servo_id, wheel_io, world_process, no_load_dps=888.0, stall_torque_nm=0.98):
        super().__init__(servo_id)
        self.io = wheel_io  # servo shaft frame
        self.no_load_dps = no_load_dps
        self.stall_torque_nm = stall_torque_nm
        self.adopted_by = None  # the engine's wire (ServoWire) this servo answers on while adopted
        self._world = world_process
        self.servo = None
        self.mount(wheel_io)

    def mount(self, wheel_io):
        """Put the servo's shaft on `wheel_io` (a wheel, in the shaft's frame): the robot is built.

        The simulator mounts each servo where the program's DriveBase says it sits (robot.py), so
        the servo's firmware starts over on the new shaft with the settings its registers hold."""
        if self.servo is not None and self.adopted_by is None:
            self._world.unsubscribe(self.servo)
        self.io = wheel_io
        self.servo = native.Servo(
            io=wheel_io,
            counts_per_rev=STEPS_PER_REV,
            max_speed_dps=self.no_load_dps,
            accel_dps2=_UNLIMITED_ACCEL_DPS2,
            decel_dps2=_UNLIMITED_ACCEL_DPS2,
        )
        self.servo.coast()
        wheel_io.silent = self.silent
        if self.adopted_by is None:
            self._configure()
            self._world.subscribe(self.servo)

    def unplug(self, silent=True):
        """Pull (or, with silent=False, restore) the servo's cable: no replies, no readings."""
        self.silent = bool(silent)
        self.io.silent = self.silent
        if self.adopted_by is not None:
            self.adopted_by.set_silent(self.servo_id, self.silent)

    # --- the shaft -------------------------------------------------------------------------

    def shaft_steps(self):
        angle = self.io.read_angle()
        if angle is None:  # unplugged: the servo is not answering anyway
            angle = self.io.true_angle_deg
        return int(round(angle / _DEG_PER_STEP))

    def speed_steps(self):
        return self.io.speed_dps / _DEG_PER_STEP

    def load(self):
        return (self.io.duty_pct or 0.0) * 10

    def _speed_cap_dps(self):
        goal = abs(self.goal_speed_steps()) * _DEG_PER_STEP
        return min(goal, self.no_load_dps) if goal else self.no_load_dps

    def written(self, touched):
        if self.adopted_by is not None:
            return  # on the engine's wire; registers are kept but not acted on
        if (
            touched(scs.REG_TORQUE_LIMIT, 2)
            or touched(scs.REG_ACCELERATION)
            or touched(scs.REG_GOAL_SPEED, 2)
        ):
            self._configure()
        if (
            touched(scs.REG_TORQUE_ENABLE)
            or touched(scs.REG_MODE)
            or touched(scs.REG_GOAL_SPEED, 2)
            or touched(scs.REG_GOAL_POSITION, 2)
            or touched(scs.REG_GOAL_TIME, 2)
        ):
            self._apply()

    def _configure(self):
        """Apply the torque limit, acceleration and speed registers to the servo's loop."""
        self.servo.set_duty_limit(max(0.1, min(100.0, self._get16(scs.REG_TORQUE_LIMIT) / 10)))
        accel = self.accel_steps2()
        accel = _UNLIMITED_ACCEL_DPS2 if accel is None else accel * _DEG_PER_STEP
        self.servo.settings(accel_dps2=accel, decel_dps2=accel, max_speed_dps=self._speed_cap_dps())

    def _apply(self):
        """Run what the mode and goal registers ask for (or coast with torque off)."""
        if not self.torque_enabled:
            self.servo.coast()
            return
        mode = self.mode
        if mode == scs.MODE_WHEEL:
            self.servo.run_speed(self.goal_speed_steps() * _DEG_PER_STEP)
        elif mode == scs.MODE_DUTY:
            self.servo.dc(max(-100.0, min(100.0, self.duty_pct())))
        else:
            self.servo.run_target(self._speed_cap_dps(), self.target_steps * _DEG_PER_STEP, then="hold")

    # --- adoption ----------------------------------------------------------------------------

    def hand_to(self, wire):
        """Answer on the bus engine's wire from now on (duty mode); the servo's own loop stands down."""
        self._world.unsubscribe(self.servo)
        self.servo.coast()
        wire.attach(self.servo_id, self.io)
        self.adopted_by = wire
        self.regs[scs.REG_MODE] = scs.MODE_DUTY

    def take_back(self):
        """Back to register control, coasting in wheel mode, as after a power cycle of the engine."""
        if self.adopted_by is not None:
            self.adopted_by.detach(self.servo_id)
        self.adopted_by = None
        self.regs[scs.REG_MODE] = scs.MODE_WHEEL
        self.regs[scs.REG_TORQUE_ENABLE] = 0
        self._put16(scs.REG_GOAL_SPEED, 0)
        self.servo.coast()
        self._world.subscribe(self.servo)


class ServoBus:
    """The daisy chain on one UART: every servo sees every packet; the addressed one answers."""

    def __init__(self):
        self.servos = {}  # id -> ServoFirmware
        self.packets = 0  # well-formed packets seen
        self.garbage = 0  # bytes dropped while resynchronising
        self._rx = b""

    def add(self, servo):
        if servo.servo_id in self.servos:
            raise ValueError(f"servo id {servo.servo_id} is already on this bus")
        self.servos[servo.servo_id] = servo
        return servo

    def servo(self, servo_id):
        return self.servos[servo_id]

    def handle(self, data):
        """Bytes the hub wrote; returns the bytes the servos answer with."""
        self._rx += bytes(data)
        out = b""
        while self._rx:
            frame = scs.decode_frame(self._rx)
            self._rx = self._rx[frame.consumed :]
            if frame.result == "need_more":
                self.garbage += frame.consumed
                break
            if frame.result != "ok":
                self.garbage += frame.consumed
                continue
            self.packets += 1
            out += self.execute(frame.id, frame.instruction, frame.params)
        return out

    def execute(self, servo_id, instruction, params):
        """One well-formed packet; returns the reply bytes (none for broadcasts but a lone ping)."""
        if instruction == scs.SYNC_WRITE:
            self._sync_write(params)
            return b""
        if servo_id == scs.BROADCAST_ID:
            if instruction == scs.PING:
                live = [s for s in self.servos.values() if not s.silent]
                # A lone servo answers a broadcast ping; several would collide into garbage.
                return live[0].reply() if len(live) == 1 else b""
            for servo in list(self.servos.values()):
                if not servo.silent and instruction == scs.WRITE and params:
                    self._write(servo, params)
            return b""
        servo = self.servos.get(servo_id)
        if servo is None or servo.silent:
            return b""
        if instruction == scs.PING:
            return servo.reply()
        if instruction == scs.READ and len(params) == 2:
            return servo.reply(servo.read(params[0], params[1]))
        if instruction == scs.WRITE and params:
            self._write(servo, params)
            return servo.reply() if servo.regs[scs.REG_RESPONSE_LEVEL] >= 1 else b""
        return b""

    def _write(self, servo, params):
        old_id = servo.servo_id
        servo.write(params[0], params[1:])
        if servo.servo_id != old_id and self.servos.get(old_id) is servo:
            del self.servos[old_id]
            self.servos[servo.servo_id] = servo

    def _sync_write(self, params):
        if len(params) < 2:
            return
        address, width = params[0], params[1]
        rows = params[2:]
        for i in range(0, len(rows) - width, width + 1):
            servo = self.servos.get(rows[i])
            if servo is not None and not servo.silent:
                servo.write(address, rows[i + 1 : i + 1 + width])


class BusEngine:
    """The serial-bus engine a DriveBase hands its wheels to (`_openbricks_native.serial_bus(uart_id)`).

    The contract is the C engine's (docs/architecture.md), whose methods it passes through; this
    class only moves each servo onto the engine's wire when it is adopted, and back to the register
    emulation when it is released.
    """

    def __init__(self, bus, wire):
        self._bus = bus
        self._wire = wire
        self._engine = native.SerialBus(wire.uart())
        self._servos = {}  # slot -> EmulatedServo

    def adopt(self, servo_id, invert=False, counts_per_rev=STEPS_PER_REV):
        """Take servo `servo_id` onto the engine and return its slot (the engine pings it on the wire)."""
        servo = self._bus.servos.get(servo_id)
        handed = servo is not None and servo.adopted_by is None and not servo.silent
        if handed:
            servo.hand_to(self._wire)
        try:
            slot = self._engine.adopt(servo_id, invert=invert, counts_per_rev=counts_per_rev)
        except BaseException:
            if handed:
                servo.take_back()
            raise
        self._servos[slot] = servo
        return slot

    def release(self, slot):
        """Give the servo back to register control (coasting); the engine may reuse the slot later."""
        self._engine.release(slot)
        self._servos.pop(slot).take_back()

    def __getattr__(self, name):
        # Everything else is the C engine's own: motor_io, angle_deg, speed_dps, load_pct, stats,
        # bus_stats, the slots' moves and flags (st_move_core), set_drive.
        return getattr(self._engine, name)
