"""Serial-bus motors after a DriveBase adopted them: their Motor calls, served by the bus engine.

When a DriveBase adopts its serial-bus wheels it hands their UART to the bus engine
(`_openbricks_native.serial_bus(uart_id)`: the firmware's C engine on the hard tick, the emulated
one in the simulator), and every motor that was on that bus is re-routed here through
`motor.adopt(port, slot)`, so `left.angle()`, `left.run_angle(...)` or an arm motor sharing the
chain keep working.

A wheel has exactly one driver at a time. Most of the time that is the drive base's controller.
A direct motor command (run_speed, run_angle, hold, dc, ...) takes its wheel back the Pybricks way:
the drive base's move ends, its other wheel is released, and the command runs on the slot: a
position move or hold on the engine's own per-slot core (the manual's st_move_core: `done()` reads
its arrival flag), a speed or duty command on a native servo controller over the slot's motor IO;
the next drive base move takes both wheels again.

The engine contract (shared with the simulator and the firmware; docs/architecture.md, "The bus engine"):
`adopt(servo_id, invert=False) -> slot`, `motor_io(slot)` (a native MotorIO, or an object with
`read_angle() -> deg | None`, `write_duty(pct)`, `coast()`), `angle_deg(slot)`, `speed_dps(slot)`,
`load_pct(slot)`, `stats(slot) -> (replies, failed_reads, failed_in_a_row)`, `release(slot)`;
st_move_core: `move(slot, speed_dps, angle_deg, then=, accel_dps2=)`, `hold(slot)`, `end_move(slot)`,
`done(slot)` (the arrival flag), `stalled(slot, load_pct, speed_dps)` (the stall flag).
Angles, speeds and loads are in the adopting motor's user frame (its invert applied).
"""

import time

from micropython import const

from openbricks import _native, estop
from openbricks.drivers.st3215 import not_responding_message

_POLL_MS = const(5)
# A wheel whose last reads all failed this many times in a row has stopped answering.
SILENT_READS = const(3)


def io_kwargs(io, side=None):
    """Keyword arguments that connect a native controller to the engine's motor IO `io`.

    A native MotorIO is ticked with no Python call (the simulator's wheels); anything else is driven
    through its three Python methods. `side` names the DriveBase keyword ("left" / "right"), or None
    for a Servo.
    """
    motor_io = _native.get("MotorIO")
    if motor_io is not None and isinstance(io, motor_io):
        return {"io": io} if side is None else {side + "_io": io}
    if side is None:
        return {"read_angle": io.read_angle, "write_duty": io.write_duty, "write_coast": io.coast}
    return {"read_" + side: io.read_angle, "write_" + side: io.write_duty, "coast_" + side: io.coast}


class BusPort:
    """What adopted motors on one bus talk to: the engine, and who drives each slot right now."""

    def __init__(self, engine, bus):
        self.engine = engine
        self.bus = bus
        self._motors = {}  # slot -> motor
        self._offsets = {}  # slot -> reset_angle offset, degrees
        self._servos = {}  # slot -> native Servo running a direct motor command
        self._limits = {}  # slot -> duty cap (percent) set before the slot had a servo
        self._base = None  # (native DriveBase, wheel slots) while a drive base drives its wheels

    # --- adoption ----------------------------------------------------------------------

    def adopt(self, motor):
        """Move `motor` onto the engine and route its Motor calls here; returns its slot."""
        slot = self.engine.adopt(motor.servo_id, invert=motor.invert)
        self._motors[slot] = motor
        self._offsets[slot] = 0.0
        motor.adopt(self, slot)
        return slot

    def slot_of(self, motor):
        for slot, known in self._motors.items():
            if known is motor:
                return slot
        return None

    def silent_error(self, slot):
        """The manual's "not responding on the bus" OSError for `slot`, or None while it answers."""
        replies, failed, in_a_row = self.engine.stats(slot)
        if in_a_row < SILENT_READS and self.engine.angle_deg(slot) is not None:
            return None
        motor = self._motors[slot]
        label = motor.side or type(motor).__name__
        return OSError(
            not_responding_message(label, motor.servo_id, slot, self.bus.where(), replies, failed, in_a_row)
        )

    # --- who drives the wheels ---------------------------------------------------------------

    def give_to_drivebase(self, controller, slots):
        """The drive base's controller drives `slots` from now on; direct commands there stand down.

        The caller subscribes the controller (after everything else has let go of the wheels)."""
        process = _native.motor_process
        for slot in slots:
            servo = self._servos.get(slot)
            if servo is not None:
                process.unsubscribe(servo)
            self.engine.end_move(slot)
        self._base = (controller, slots)
        estop.on_engage(self.halt)  # again after each program boundary, which forgets the halts

    def forget_drivebase(self, controller):
        """`controller` no longer drives this port's wheels (DriveBase.close())."""
        if self._base is not None and self._base[0] is controller:
            self._base = None

    def _take_from_drivebase(self, slot):
        base = self._base
        if base is None or slot not in base[1]:
            return
        controller, slots = base
        self._base = None
        controller.stop("coast")  # releases both wheels now; the other one stays free
        _native.motor_process.unsubscribe(controller)

    def halt(self):
        """The e-stop's halt: every wheel and accessory this port drives is released at once."""
        if self._base is not None:
            self._base[0].stop("coast")
        for servo in self._servos.values():
            servo.coast()
        for slot in self._motors:
            self.engine.end_move(slot)
            self.engine.motor_io(slot).coast()

    def _servo(self, slot, what, motion=True):
        """The native servo controller that runs direct commands on `slot`, now driving it.

        A `motion` command is refused while the e-stop is engaged; a stop (brake, hold) is not,
        as on a motor no drive base adopted."""
        motor = self._motors[slot]
        if motion:
            estop.check("%s.%s" % (motor.side or type(motor).__name__, what))
        self._take_from_drivebase(slot)
        self.engine.end_move(slot)
        servo = self._servos.get(slot)
        if servo is None:
            kwargs = io_kwargs(self.engine.motor_io(slot))
            kwargs["max_speed_dps"] = motor.max_dps
            if motor.accel_dps2 > 0:  # 0 is the servo's "no ramp"; the native default ramps steeply
                kwargs["accel_dps2"] = motor.accel_dps2
            servo = _native.Servo(counts_per_rev=_native.scs.COUNTS_PER_REV, **kwargs)
            if slot in self._limits:
                servo.set_duty_limit(self._limits[slot])
            self._servos[slot] = servo
        _native.motor_process.subscribe(servo)
        estop.on_engage(self.halt)
        return servo

    def _move_core(self, slot, what, motion=True):
        """Make the engine's own per-slot core (st_move_core) the driver of `slot`."""
        motor = self._motors[slot]
        if motion:
            estop.check("%s.%s" % (motor.side or type(motor).__name__, what))
        self._take_from_drivebase(slot)
        servo = self._servos.get(slot)
        if servo is not None:
            _native.motor_process.unsubscribe(servo)
        estop.on_engage(self.halt)

    def _checked(self, slot):
        error = self.silent_error(slot)
        if error is not None:
            raise error

    # --- the Motor calls of an adopted motor (user frame, slot first) --------------------------

    def angle(self, slot):
        raw = self.engine.angle_deg(slot)
        return None if raw is None else raw + self._offsets[slot]

    def reset_angle(self, slot, angle=0):
        self._checked(slot)
        self._offsets[slot] = angle - self.engine.angle_deg(slot)

    def speed(self, slot):
        if self.engine.angle_deg(slot) is None:
            return None
        return self.engine.speed_dps(slot)

    def load(self, slot):
        if self.engine.angle_deg(slot) is None:
            return None
        return self.engine.load_pct(slot) / 100 * self._motors[slot].STALL_TORQUE_MNM

    def stalled(self, slot):
        self._checked(slot)
        servo = self._servos.get(slot)
        if servo is not None and self._base is None and servo.stalled():
            return True
        motor = self._motors[slot]
        return self.engine.stalled(slot, motor.STALL_LOAD_PCT, motor.STALL_SPEED_DPS)

    def run_speed(self, slot, deg_per_s):
        self._checked(slot)
        self._servo(slot, "run_speed").run_speed(deg_per_s)

    def dc(self, slot, duty):
        self._checked(slot)
        self._servo(slot, "dc").dc(max(-100, min(100, duty)))

    def brake(self, slot):
        # Like the servo's own brake: ramp to zero speed and hold that rate.
        self._servo(slot, "brake", motion=False).run_speed(0)

    def coast(self, slot):
        # Releasing a wheel is always allowed, e-stop or not, and needs no controller of its own.
        self._take_from_drivebase(slot)
        self.engine.end_move(slot)
        servo = self._servos.get(slot)
        if servo is not None:
            servo.coast()
        else:
            self.engine.motor_io(slot).coast()

    def hold(self, slot):
        self._checked(slot)
        self._move_core(slot, "hold", motion=False)
        self.engine.hold(slot)

    def set_duty_limit(self, slot, limit_pct):
        self._limits[slot] = limit_pct
        servo = self._servos.get(slot)
        if servo is not None:
            servo.set_duty_limit(limit_pct)

    def run_angle(self, slot, deg_per_s, target_angle, wait=True, then="coast"):
        if deg_per_s == 0:
            raise ValueError("run_angle(deg_per_s=0): the move would never finish; give a non-zero speed")
        self._checked(slot)
        self._move_core(slot, "run_angle")
        motor = self._motors[slot]
        accel = motor.accel_dps2 if motor.accel_dps2 > 0 else None
        self.engine.move(slot, abs(deg_per_s), target_angle, then=then, accel_dps2=accel)
        if wait:
            while not self.done(slot):
                time.sleep_ms(_POLL_MS)

    def done(self, slot):
        """The arrival flag of the slot's move (st_move_core): the tick advanced it, nothing more to do."""
        try:
            return self.engine.done(slot)
        except OSError:
            raise self.silent_error(slot) or OSError(
                "%s lost its position feedback mid-move" % (self._motors[slot].side or "the motor")
            ) from None

    def release_all(self):
        """Hand every slot back to the engine (coasting); the motors stay unusable until re-adopted."""
        process = _native.motor_process
        if self._base is not None:
            process.unsubscribe(self._base[0])
            self._base = None
        for slot in list(self._motors):
            servo = self._servos.pop(slot, None)
            if servo is not None:
                process.unsubscribe(servo)
            self.engine.end_move(slot)
            self._motors.pop(slot).adopt(None, None)
            self.engine.release(slot)
