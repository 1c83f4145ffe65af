"""How each chassis is wired to the simulated hub: the devices a program finds on its buses and pins.

The serial-bus build (st3032) carries two ST-3032 servos on UART1 (TX 14,
RX 41). The DC build (jgb37) has two JGB37-520 motors behind an L298N bridge
with their quadrature encoders on PCNT units, on the manual's GPIO map.

A real robot is wired the way its program says, so the simulated one is too:
the motor a program passes to DriveBase as `left` drives the left wheel
(`place_wheels`). Which way a motor turns its wheel differs by build, because
what a builder can change differs:

- Serial bus: a servo turns the way its horn faces and has no leads to swap,
  so the chassis has exactly one mirrored side, as any robot with two
  identical motors facing outwards does. The mirrored wheel is the one the
  program inverts (`mount_signs`); when it inverts neither (or both), the
  right one stays mirrored and the robot does what that program would make
  the real one do: spin where it meant to drive straight.
- DC: a builder wires a mirrored motor with its leads (motor and encoder)
  swapped, or not and inverts it in the program; either way the robot drives.
  So each bridge motor is wired to match the driver the program builds on
  its channel (`bridge_sign`): forward for the driver is forward for the
  wheel. The manual's listing, inverting neither motor, gets the mirrored
  right motor with its leads swapped; the bundled example, inverting the
  right one, gets them as they come. A program that inverts exactly one
  motor describes a consistent robot whichever one it is (inverting the
  unmirrored left one says its leads are swapped and the right one's too),
  and drives straight as that robot would. Until a program builds its
  drivers (or when nothing watches it build them: a Simulation driven
  directly), the chassis is the bundled example's: right motor mirrored,
  leads as they come.

Until a DriveBase says otherwise, servo id 1 and the first bridge channel
drive the left wheel.
"""

from dataclasses import dataclass

from .serial_bus import BusEngine, EmulatedServo, ServoBus

SERVO_UART = 1
SERVO_IDS = (1, 2)  # left, right until the program's DriveBase places them
LEFT, RIGHT = 0, 1
# A wheel's joint turns forward-positive on both sides; a motor mounted mirrored sees it negated.
DEFAULT_MIRRORED = RIGHT


def mount_signs(left_invert=False, right_invert=True):
    """(left, right) shaft-to-wheel signs of the serial-bus chassis whose program inverts these servos.

    A servo cannot be rewired, only turned round: one side is mirrored whatever the program says, so
    neither or both inverted keeps the default and the robot spins as the real one would."""
    mirrored = DEFAULT_MIRRORED
    if bool(left_invert) != bool(right_invert):
        mirrored = LEFT if left_invert else RIGHT
    return tuple(-1 if wheel == mirrored else 1 for wheel in (LEFT, RIGHT))


MOUNT_SIGNS = mount_signs()


@dataclass(frozen=True)
class BridgeChannel:
    in1: int
    in2: int
    enable: int
    encoder_a: int
    encoder_b: int

    def swapped(self, in1, in2, enable):
        """Whether a driver on these pins names IN2 as its IN1; None if they are not this channel."""
        if enable != self.enable or {in1, in2} != {self.in1, self.in2}:
            return None
        return in1 != self.in1


def bridge_sign(invert, swapped_pins=False):
    """Shaft-to-wheel sign of a DC motor wired for the driver the program builds on its channel.

    The leads (motor and encoder together) are connected so that the driver's forward turns the wheel
    forward: a driver with invert=True, or one that names the channel's IN2 as its IN1, gets them the
    other way round from one without."""
    return -1 if bool(invert) != bool(swapped_pins) else 1


# Manual 2.7: left IN1/IN2 = 1/2, ENA = 17, encoder 7/8; right IN3/IN4 = 9/10, ENB = 11, encoder 12/13.
JGB37_CHANNELS = (BridgeChannel(1, 2, 17, 7, 8), BridgeChannel(9, 10, 11, 12, 13))


class SerialBusWiring:
    """Two emulated ST-3032s on UART1 and the engine a DriveBase adopts them onto."""

    def __init__(self, physics, board, world_process):
        motor = physics.chassis.motor
        self.bus = ServoBus()
        for wheel, (servo_id, sign) in enumerate(zip(SERVO_IDS, MOUNT_SIGNS, strict=True)):
            io = physics.wheel_io(wheel, sign)
            self.bus.add(
                EmulatedServo(servo_id, io, world_process, motor.no_load_speed_dps, motor.stall_torque_nm)
            )
        board.attach_uart(SERVO_UART, self.bus)
        self._physics = physics
        # The firmware's C engine over the emulated 1 Mbaud wire. A servo answers there once adopted,
        # driving the shaft it is mounted on (EmulatedServo.io, set by place_wheels below): that
        # mount is the one place a servo id meets a wheel.
        self.engine = BusEngine(self.bus, physics.servo_wire())

    def place_wheels(self, left, right):
        """Mount the servos the program's DriveBase names: `left`/`right` = ((uart_id, servo_id), invert).

        Servos already adopted by an earlier drive base stay where they are (the robot is built);
        a servo this robot does not carry (or another kind of motor) is left to its driver."""
        servos = [
            self.bus.servos.get(key[1]) if isinstance(key, tuple) and key[0] == SERVO_UART else None
            for key in (left[0], right[0])
        ]
        if None in servos or servos[0] is servos[1] or any(s.adopted_by is not None for s in servos):
            return
        signs = mount_signs(left[1], right[1])
        for wheel, servo in enumerate(servos):
            if (servo.io.wheel, servo.io.sign) != (wheel, signs[wheel]):
                servo.mount(self._physics.wheel_io(wheel, signs[wheel]))

    def build_motor(self, in1, in2, pwm, invert):
        """A bridge driver on this robot drives nothing: it has no bridge."""

    def serial_bus(self, uart_id):
        if uart_id != SERVO_UART:
            raise OSError(
                f"no serial-bus servos on UART{uart_id} in the simulator: the simulated robot's servos "
                f"are on UART{SERVO_UART}"
            )
        return self.engine


class _Bridge:
    """One L298N channel driving one wheel: IN1/IN2 pick the direction, the EN duty the strength."""

    def __init__(self, board, io, channel):
        self._board = board
        self.io = io  # the wheel this channel's motor turns (BridgeWiring mounts it)
        self.channel = channel
        self._enable = 0.0
        for pin in (channel.in1, channel.in2):
            board.watch_output(pin, self._changed)
        board.watch_output(channel.enable, self._enable_changed)

    def _level(self, pin):
        driven = self._board.pins.get(pin)
        return driven._out if driven is not None and driven._is_output() else 0

    def _enable_changed(self, _pin, value):
        self._enable = float(value)
        self._changed(_pin, value)

    def _changed(self, _pin, _value):
        in1, in2 = self._level(self.channel.in1), self._level(self.channel.in2)
        if self._enable <= 0.0 or (in1 == 0 and in2 == 0):
            self.io.coast()
        elif in1 and in2:
            self.io.write_duty(0.0)  # both low sides on: the winding is shorted
        else:
            self.io.write_duty(100.0 * self._enable * (1 if in1 else -1))


class BridgeWiring:
    """Two JGB37-520s behind an L298N, encoders on PCNT."""

    def __init__(self, physics, board, world_process):
        self._physics = physics
        self._board = board
        self.bridges = []
        for wheel, (channel, sign) in enumerate(zip(JGB37_CHANNELS, MOUNT_SIGNS, strict=True)):
            self.bridges.append(_Bridge(board, None, channel))
            self._mount(self.bridges[-1], wheel, sign)

    def _mount(self, bridge, wheel, sign):
        counts = self._physics.chassis.motor.counts_per_rev
        bridge.io = self._physics.wheel_io(wheel, sign, counts)
        self._board.set_encoder(bridge.channel.encoder_a, _edges(bridge.io, counts))

    def build_motor(self, in1, in2, pwm, invert):
        """A program builds a bridge driver on (in1, in2, pwm): wire its channel's motor to match it
        (`bridge_sign`), on whichever wheel the channel drives. Pins of no channel are the driver's
        business (it drives nothing here)."""
        for bridge in self.bridges:
            swapped = bridge.channel.swapped(in1, in2, pwm)
            if swapped is not None:
                self._remount(bridge, bridge.io.wheel, bridge_sign(invert, swapped))
                return

    def place_wheels(self, left, right):
        """Mount the motors the program's DriveBase names: `left`/`right` = (encoder_a_pin, invert).

        The motors passed to DriveBase decide which wheel is which, not their pin numbers; each keeps
        the leads its driver was wired with (`build_motor`)."""
        by_pin = {bridge.channel.encoder_a: bridge for bridge in self.bridges}
        bridges = [by_pin.get(pin) if isinstance(pin, int) else None for pin, _ in (left, right)]
        if None in bridges or bridges[0] is bridges[1]:
            return
        for wheel, bridge in enumerate(bridges):
            self._remount(bridge, wheel, bridge.io.sign)

    def _remount(self, bridge, wheel, sign):
        if (bridge.io.wheel, bridge.io.sign) != (wheel, sign):
            bridge.io.coast()
            self._mount(bridge, wheel, sign)

    def serial_bus(self, uart_id):
        raise OSError(f"the simulated DC-motor robot has no serial-bus servos (UART{uart_id})")


def _edges(io, counts_per_rev):
    def edges():
        return int(round(io.true_angle_deg * counts_per_rev / 360.0))

    return edges


WIRINGS = {"st3032": SerialBusWiring, "jgb37": BridgeWiring}


def wire(physics, board, world_process):
    """The devices of physics' chassis, attached to board."""
    try:
        wiring = WIRINGS[physics.chassis.name]
    except KeyError:
        raise ValueError(
            "chassis {!r} has no hub wiring in the simulator; known: {}".format(
                physics.chassis.name, ", ".join(WIRINGS)
            )
        ) from None
    return wiring(physics, board, world_process)


__all__ = ["BusEngine", "wire"]
