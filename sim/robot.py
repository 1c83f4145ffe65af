"""How each chassis is wired to the simulated hub: the devices a program finds on its buses and pins.

The serial-bus build (st3032) carries two ST-3032 servos on UART1 (TX 14,
RX 41): id 1 drives the left wheel, id 2 the right one, mounted mirrored, so
a program builds the right motor with invert=True exactly as on the real
robot. The DC build (jgb37) has two JGB37-520 motors behind an L298N bridge
with their quadrature encoders on PCNT units, on the manual's GPIO map.
"""

from dataclasses import dataclass

from .serial_bus import BusEngine, EmulatedServo, ServoBus

SERVO_UART = 1
SERVO_IDS = (1, 2)  # left, right, as the manual's examples assume
# A wheel's joint turns forward-positive on both sides; the right motor is mounted mirrored.
MOUNT_SIGNS = (1, -1)


@dataclass(frozen=True)
class BridgeChannel:
    in1: int
    in2: int
    enable: int
    encoder_a: int
    encoder_b: int


# Manual 2.7: left IN1/IN2 = 1/2, ENA = 17, encoder 7/8; right IN3/IN4 = 9/10, ENB = 11, encoder 12/13.
JGB37_CHANNELS = (BridgeChannel(1, 2, 17, 7, 8), BridgeChannel(9, 10, 11, 12, 13))


class SerialBusWiring:
    """Two emulated ST-3032s on UART1 and the engine a DriveBase adopts them onto."""

    def __init__(self, physics, board, world_process):
        motor = physics.chassis.motor
        self.bus = ServoBus()
        self.wheel_of = {}  # servo id -> wheel index
        for wheel, (servo_id, sign) in enumerate(zip(SERVO_IDS, MOUNT_SIGNS, strict=True)):
            io = physics.wheel_io(wheel, sign)
            self.bus.add(
                EmulatedServo(servo_id, io, world_process, motor.no_load_speed_dps, motor.stall_torque_nm)
            )
            self.wheel_of[servo_id] = wheel
        board.attach_uart(SERVO_UART, self.bus)
        self._physics = physics
        self.engine = BusEngine(self.bus, self._engine_io, f"UART{SERVO_UART} tx=14 rx=41")

    def _engine_io(self, servo, invert):
        wheel = self.wheel_of.get(servo.servo_id)
        if wheel is None:  # re-IDed after wiring: find it by its IO
            wheel = servo.io.wheel
        sign = MOUNT_SIGNS[wheel] * (-1 if invert else 1)
        return self._physics.wheel_io(wheel, sign)

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
        self._io = io
        self._channel = channel
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
        in1, in2 = self._level(self._channel.in1), self._level(self._channel.in2)
        if self._enable <= 0.0 or (in1 == 0 and in2 == 0):
            self._io.coast()
        elif in1 and in2:
            self._io.write_duty(0.0)  # both low sides on: the winding is shorted
        else:
            self._io.write_duty(100.0 * self._enable * (1 if in1 else -1))


class BridgeWiring:
    """Two JGB37-520s behind an L298N, encoders on PCNT."""

    def __init__(self, physics, board, world_process):
        counts = physics.chassis.motor.counts_per_rev
        self.bridges = []
        for wheel, (channel, sign) in enumerate(zip(JGB37_CHANNELS, MOUNT_SIGNS, strict=True)):
            io = physics.wheel_io(wheel, sign, counts)
            self.bridges.append(_Bridge(board, io, channel))
            board.set_encoder(channel.encoder_a, _edges(io, counts))

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
