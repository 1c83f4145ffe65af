"""A brushed DC gear motor on the fake board: H-bridge pins in, encoder signals out.

    lines = QuadratureLines(7, 8)       # A/B wires of an encoder, driven edge by edge
    lines.move(+40)                     # ten quadrature cycles forward: IRQs fire per edge

    rig = DCMotorRig(plant, in1=1, in2=2, pwm=17, counts_per_rev=1320, encoder=lines)

The rig is a timer on the virtual clock: every step it reads what the driver
put on the bridge (IN1/IN2 levels and the EN duty), advances `plant` (any
object with `step(duty_pct or None, dt_s)` and `angle_deg`; None = coasting),
and moves the encoder (quadrature lines, or the edges a PCNT unit counts) to the
plant's angle.
"""

from . import bounded, clock
from .machine import board

_PHASES = ((0, 0), (1, 0), (1, 1), (0, 1))  # A leading B


class QuadratureLines:
    """The A and B signals of an encoder, starting at rest with both low."""

    def __init__(self, pin_a, pin_b):
        self.pin_a = pin_a
        self.pin_b = pin_b
        self.count = 0
        board.inputs[pin_a] = 0
        board.inputs[pin_b] = 0

    def move(self, counts):
        """Step the lines through `counts` edges (negative: backwards), one edge at a time."""
        step = 1 if counts > 0 else -1
        for _ in range(abs(int(counts))):
            self.count += step
            level_a, level_b = _PHASES[self.count % 4]
            board.set_input(self.pin_a, level_a)
            board.set_input(self.pin_b, level_b)


class ShaftEdges:
    """The edges a shaft's encoder puts on its A line, reported straight to the PCNT unit counting
    that line (board.set_encoder), as the simulator's wheels report theirs."""

    def __init__(self, pin_a):
        self.edges = 0
        board.set_encoder(pin_a, self._edges)

    def _edges(self):
        return self.edges

    def move(self, counts):
        self.edges += int(counts)


class DCMotorRig:
    def __init__(self, plant, in1, in2, pwm, counts_per_rev, encoder, step_us=250):
        self.plant = plant
        self.in1 = in1
        self.in2 = in2
        self.pwm = pwm
        self.counts_per_rev = counts_per_rev
        self.encoder = encoder
        self.step_us = step_us
        self.wall_deg = None  # an end stop the shaft cannot pass (approached from below if above start)
        self.duty_log = []  # (time ms, duty or None) whenever the bridge output changes
        self._counts = self._plant_counts()
        self._steps = clock.every_us(step_us, self._step)

    def _plant_counts(self):
        angle = self.plant.angle_deg * self.counts_per_rev / 360.0
        return int(angle // 1)

    def bridge_duty(self):
        """Duty % the winding sees (0 = shorted/braking), or None when the bridge is off (coasting)."""
        pin1 = board.pins.get(self.in1)
        pin2 = board.pins.get(self.in2)
        pwm = board.pwms.get(self.pwm)
        if pin1 is None or pin2 is None or pwm is None:
            return None
        a, b = pin1.value(), pin2.value()
        enable = pwm.duty_u16() * 100.0 / 65535
        if enable == 0 or (a == 0 and b == 0):
            return None
        if a == b:
            return 0.0
        return enable if a else -enable

    def _step(self):
        duty = self.bridge_duty()
        if not self.duty_log or self.duty_log[-1][1] != duty:
            bounded.append(self.duty_log, (clock.now_us() // 1000, duty))
        self.plant.step(duty, self.step_us / 1e6)
        if self.wall_deg is not None and self.plant.angle_deg >= self.wall_deg:
            self.plant.angle_deg = self.wall_deg
            self.plant.speed_dps = 0.0
            self.plant.blocked = (duty or 0) > 0  # pushing into it; backing off frees it
        counts = self._plant_counts()
        if counts != self._counts:
            self.encoder.move(counts - self._counts)
            self._counts = counts

    def close(self):
        self._steps.cancel()
