"""How a DriveBase's two motors are connected to its controller, by motor family.

- Serial-bus servos (ST3215Motor, ST3032Motor): adopted onto the bus engine, which drives each
  wheel's bridge in duty mode and reads its encoder; the controller ticks through the engine's
  motor IO (natively in the simulator and on the hub).
- Encoder motors (JGB37Motor, MG370Motor): the controller drives the motor's own IO (encoder in,
  bridge out) while the motor's native servo core stands down (`give_to_drivebase`). A direct
  command on either motor takes its wheel back through `let_go()`: the drive base's move ends and
  both wheels coast, as Pybricks does when a drive base motor is used directly.
- Anything else with dc/brake/coast (L298NMotor, TB6612Motor, or an encoder motor on a build without
  the native cores): open loop. No feedback, so no controller.

Each pair answers the same questions for the DriveBase: the controller's IO keywords, how to make the
controller the one driver of both wheels, whether both wheels still answer, and what a watchdog halt
means in words the user can act on.
"""

import time

from micropython import const

from openbricks import _native
from openbricks.drivers.st3215 import not_responding_message
from openbricks.robotics.bus_port import BusPort, io_kwargs

SIDES = ("left", "right")
# How long a freshly adopted wheel may take to deliver its first reading (a hard-tick engine reads
# every slot a few times in this window).
_FIRST_READING_MS = const(50)

_KIND_PHRASES = {
    "serial-bus": "a serial-bus servo",
    "encoder": "an encoder motor",
    "open-loop": "an open-loop motor",
}

_ports = {}  # uart id -> BusPort of the engine that owns that UART
# id(motor) -> the drive base controller driving it; a motor has one driver, so a second drive base
# built over the same motors takes them from the first instead of fighting it every tick.
_drivers = {}


def _is_serial_bus(motor):
    return hasattr(motor, "adopt") and hasattr(getattr(motor, "bus", None), "hand_over")


def _is_encoder_motor(motor):
    # closed_loop is False on a build without the native servo core: such a motor is open loop.
    return callable(getattr(motor, "give_to_drivebase", None)) and getattr(motor, "closed_loop", False)


def pair_for(left, right, drive="duty"):
    """The pair class that fits `left` and `right`, built; raises when they cannot share a chassis.

    `drive` ("duty" or "wheel") is how serial-bus wheels are actuated; other motors have one way."""
    for side, motor in (("left", left), ("right", right)):
        for method in ("dc", "brake", "coast"):
            if not callable(getattr(motor, method, None)):
                raise TypeError(
                    "DriveBase %s motor: %r is not a motor (it has no %s()); pass motor objects such as "
                    "ST3032Motor, JGB37Motor or L298NMotor" % (side, motor, method)
                )
    if left is right:
        raise ValueError("DriveBase: left and right are the same motor object; give it two motors")
    kinds = [
        "serial-bus" if _is_serial_bus(m) else "encoder" if _is_encoder_motor(m) else "open-loop"
        for m in (left, right)
    ]
    if kinds[0] != kinds[1]:
        raise TypeError(
            "DriveBase: the left motor (%s) is %s but the right one (%s) is %s; both wheels need the same "
            "kind of feedback to be driven as one chassis"
            % (type(left).__name__, _KIND_PHRASES[kinds[0]], type(right).__name__, _KIND_PHRASES[kinds[1]])
        )
    if drive != "duty" and kinds[0] != "serial-bus":
        raise ValueError(
            "DriveBase(drive=%r) selects the serial-bus servos' own speed controller; %s / %s: each is %s, "
            "with none of its own; leave drive at 'duty'"
            % (drive, type(left).__name__, type(right).__name__, _KIND_PHRASES[kinds[0]])
        )
    if kinds[0] == "serial-bus":
        return SerialBusPair(left, right, drive)
    if kinds[0] == "encoder":
        return EncoderPair(left, right)
    return OpenLoopPair(left, right)


class _Pair:
    kind = ""
    closed_loop = True

    def __init__(self, left, right):
        self.motors = (left, right)

    def take(self, controller):
        """Make `controller` the one driver of both wheels (subscribed to motor_process)."""
        process = _native.motor_process
        for motor in self.motors:
            previous = _drivers.get(id(motor))
            if previous is not None and previous is not controller:
                previous.stop("coast")
                process.unsubscribe(previous)
            _drivers[id(motor)] = controller
        self._hand_over(controller, process)
        process.subscribe(controller)

    def _hand_over(self, controller, process):
        """Stand down whatever else drives the wheels (the motors' own controllers)."""

    def release(self, controller):
        """Stop ticking `controller`; the motors have no drive base driver afterwards."""
        _native.motor_process.unsubscribe(controller)
        for motor in self.motors:
            if _drivers.get(id(motor)) is controller:
                del _drivers[id(motor)]

    def check(self):
        """Raise if a wheel has stopped answering; a pair that cannot tell does nothing."""

    def fault_error(self, sides, native_error):
        """The error for a watchdog halt on `sides` ("left", "right", "gyro")."""
        return native_error


class EncoderPair(_Pair):
    kind = "encoder"

    def __init__(self, left, right):
        _Pair.__init__(self, left, right)
        self._controller = None  # the drive base controller driving both bridges, while one does

    def controller_io(self):
        io = {}
        for i, side in enumerate(SIDES):
            io.update(io_kwargs(self.motors[i].motor_io(), side))
        return io

    def _hand_over(self, controller, process):
        self._controller = controller
        for motor in self.motors:
            motor.give_to_drivebase(self)  # its own core stands down: one driver per bridge

    def let_go(self):
        """A direct command on one wheel took it back: end the move and free both wheels (coasting)."""
        controller = self._controller
        if controller is not None:
            controller.stop("coast")
            self.release(controller)

    def release(self, controller):
        _Pair.release(self, controller)
        for motor in self.motors:
            motor.forget_drivebase(self)
        if self._controller is controller:
            self._controller = None


class OpenLoopPair(_Pair):
    kind = "open-loop"
    closed_loop = False


class SerialBusPair(_Pair):
    """Two serial-bus wheels adopted onto the bus engine (8.2): one controller, no Python loop."""

    kind = "serial-bus"

    def __init__(self, left, right, drive="duty"):
        _Pair.__init__(self, left, right)
        serial_bus = _engine_factory(left)
        for i, side in enumerate(SIDES):
            motor = self.motors[i]
            motor.set_label(side + " wheel", motor.slot)
            if not motor.bus.handed_over and not motor.ping():
                replies, failed, in_a_row = motor.bus.stats(motor.servo_id)
                raise OSError(
                    not_responding_message(
                        side + " wheel", motor.servo_id, None, motor.bus.where(), replies, failed, in_a_row
                    )
                )
        self.wheels = tuple(_adopt(motor, serial_bus) for motor in self.motors)
        for motor in self.motors:
            type(motor).migrate_bus_to_native(motor.bus, skip=self.motors)
        for i, side in enumerate(SIDES):
            self.motors[i].set_label(side + " wheel", self.wheels[i][1])
            port, slot = self.wheels[i]
            port.engine.set_drive(slot, drive, self.motors[i].max_dps)
        self._await_first_readings()
        self.check()

    def _await_first_readings(self):
        deadline = time.ticks_add(time.ticks_ms(), _FIRST_READING_MS)
        for port, slot in self.wheels:
            while port.engine.angle_deg(slot) is None:
                if time.ticks_diff(deadline, time.ticks_ms()) <= 0:
                    break
                time.sleep_ms(1)

    def controller_io(self):
        io = {}
        for i, side in enumerate(SIDES):
            port, slot = self.wheels[i]
            io.update(io_kwargs(port.engine.motor_io(slot), side))
        return io

    def _hand_over(self, controller, process):
        by_port = {}
        for port, slot in self.wheels:
            by_port.setdefault(id(port), (port, []))[1].append(slot)
        for port, slots in by_port.values():
            port.give_to_drivebase(controller, slots)

    def release(self, controller):
        _Pair.release(self, controller)
        for port, _slot in self.wheels:
            port.forget_drivebase(controller)

    def check(self):
        for port, slot in self.wheels:
            error = port.silent_error(slot)
            if error is not None:
                raise error

    def fault_error(self, sides, native_error):
        for i, side in enumerate(SIDES):
            port, slot = self.wheels[i]
            if side in sides:
                error = port.silent_error(slot)
                if error is not None:
                    return error
                # Silent long enough to halt, answering again by now: still name the wheel.
                motor = self.motors[i]
                replies, failed, in_a_row = port.engine.stats(slot)
                return OSError(
                    not_responding_message(
                        side + " wheel", motor.servo_id, slot, port.bus.where(), replies, failed, in_a_row
                    )
                )
        return native_error


def release_ports():
    """Hand every adopted slot back to its engine and forget the ports and drive-base drivers.

    The launcher calls this when a program ends: the motors and controllers those records point at
    belong to the finished program, and the next one adopts its own wheels again (a stale port would
    refuse them, and a stale driver would be "stopped" through motors that no longer exist).
    """
    ports = tuple(_ports.values())
    _ports.clear()
    _drivers.clear()
    for port in ports:
        port.release_all()


def _adopt(motor, serial_bus):
    """(port, slot) of `motor` on its bus' engine, handing the UART over on first use."""
    bus = motor.bus
    port = _ports.get(bus.uart_id)
    if port is None or port.bus is not bus:
        if bus.handed_over:
            raise RuntimeError(
                "UART%d was handed to a bus engine this runtime no longer knows; restart the program"
                % bus.uart_id
            )
        uart_id, tx, rx, baud, dir_pin = bus.hand_over()
        port = _ports[uart_id] = BusPort(serial_bus(uart_id, tx=tx, rx=rx, baud=baud, dir_pin=dir_pin), bus)
    slot = port.slot_of(motor)
    if slot is None:
        slot = port.adopt(motor)
    return port, slot


def _engine_factory(motor):
    """`_openbricks_native.serial_bus`, or the error 8.2 asks for when this runtime has no engine."""
    serial_bus = _native.get("serial_bus")
    if serial_bus is None:
        raise RuntimeError(
            "DriveBase over serial-bus motors needs the native bus engine (the hub firmware's hard tick, "
            "or the simulator's emulated bus) and this runtime has none, so there is no controller for "
            "%s (servo id %d on %s); run the program on an openbricks hub or in `openbricks sim`"
            % (type(motor).__name__, motor.servo_id, motor.bus.where())
        )
    return serial_bus
