"""Feetech ST-3215 / ST-3032 servos for the runtime's tests: the simulator's servo firmware on a test shaft.

    bus = ScsBus()
    left = bus.add(FakeServo(1))
    machine.board.attach_uart(1, bus)

The register file, the bus (PING, READ, WRITE, SYNC WRITE, broadcast) and how
writes set goals are the simulator's (sim/serial_bus.py, the codec's register
map in `scs`). What a test needs beyond the simulator is a shaft it can hold in
its hand without MuJoCo: one the virtual clock advances, in encoder counts. Wheel
mode (1) tracks goal speed under the acceleration register, position mode (0)
runs a trapezoid to a goal inside one turn (never across the 0/4095 seam, as the
real single-turn mode does), open-loop mode (2) spins at a duty share of no-load
speed, and step mode (3) moves by a signed relative step while Present Position
reads the steps still to go. Pushing past 80 % of stall for 2 s unloads the
torque and flags overload, as the firmware's protection does. Tests can silence
a servo, change its id, block its shaft or put a wall in its way, and read back
every write, every packet and the true shaft angle.
"""

import math
import sys

from . import bounded, clock

if sys.implementation.name == "micropython":
    from serial_bus import ServoBus, ServoFirmware, from_sign_magnitude, scs
else:
    from openbricks_sim.serial_bus import ServoBus, ServoFirmware, from_sign_magnitude, scs

__all__ = ("FakeServo", "ScsBus", "from_sign_magnitude", "scs")

COUNTS_PER_REV = scs.COUNTS_PER_REV
_STEP_US = 1000  # shaft integration step
_FREEWHEEL_TAU_S = 0.03  # a coasting shaft behind a ~1:200 gearbox stops almost at once
_DUTY_TAU_S = 0.05  # open-loop speed response to a duty step
_OVERLOAD_LOAD = 800  # 0.1 % units: the datasheet's "> 80 % of stall ..."
_OVERLOAD_US = 2_000_000  # "... for 2 s" unloads the torque and flags overload


class FakeServo(ServoFirmware):
    """One servo: the simulator's register file over a kinematic shaft. Angles and speeds in counts."""

    def __init__(self, servo_id, no_load_dps=888.0):
        super().__init__(servo_id)
        self.max_cps = no_load_dps * COUNTS_PER_REV / 360.0
        self.position = 0.0  # true shaft position, counts, unbounded
        self.velocity = 0.0  # counts/s
        self.load_permille = 0.0  # 0.1 % of stall, signed
        self.blocked = False
        self.wall = None  # (position counts, side): the shaft cannot pass it
        self.writes = []  # (address, bytes) of every write it accepted, in order
        self._pushing_us = 0
        self._last_us = clock.now_us()

    # --- test handles ---------------------------------------------------------

    @property
    def torque_enabled(self):
        self.advance()  # overload protection may have unloaded it since the last access
        return self._torque_on()

    def _torque_on(self):
        return self.regs[scs.REG_TORQUE_ENABLE] == 1

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

    # --- what the firmware reads of the shaft -------------------------------------

    def shaft_steps(self):
        return self.position

    def speed_steps(self):
        return self.velocity

    def load(self):
        return self.load_permille

    def write(self, address, data):
        self.advance()
        bounded.append(self.writes, (address, bytes(data)))
        super().write(address, data)

    def written(self, touched):
        if touched(scs.REG_TORQUE_ENABLE) and self.regs[scs.REG_TORQUE_ENABLE]:
            self.error_flags &= ~scs.FLAG_OVERLOAD
            self._pushing_us = 0

    # --- the shaft ------------------------------------------------------------------

    def _accel_cps2(self):
        accel = self.accel_steps2()
        return 1e9 if accel is None else float(accel)

    def _speed_cap_cps(self):
        goal = abs(self.goal_speed_steps())
        return min(goal, self.max_cps) if goal else self.max_cps

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
            self.target_steps = self.position  # the firmware keeps the goal at present while unloaded
            self.velocity *= math.exp(-dt / _FREEWHEEL_TAU_S)
            if abs(self.velocity) < 1.0:
                self.velocity = 0.0
        elif mode == scs.MODE_WHEEL:
            goal = max(-self.max_cps, min(self.max_cps, self.goal_speed_steps()))
            self.velocity = self._ramp(goal, dt)
            effort = goal
        elif mode == scs.MODE_DUTY:
            duty = self.duty_pct() / 100.0
            wanted = duty * self.max_cps
            self.velocity += (wanted - self.velocity) * min(1.0, dt / _DUTY_TAU_S)
            effort = duty
        else:
            error = self.target_steps - self.position
            if abs(error) < 0.5 and abs(self.velocity) < self._accel_cps2() * dt + 1:
                self.position = self.target_steps
                self.velocity = 0.0
            else:
                cap = self._speed_cap_cps()
                wanted = math.sqrt(2.0 * self._accel_cps2() * max(0.0, abs(error) - 0.5))
                wanted = min(cap, wanted)
                wanted = wanted if error > 0 else -wanted
                self.velocity = self._ramp(wanted, dt)
                # Land exactly rather than hop over the target inside one step.
                landing = self.position + self.velocity * dt
                if (self.velocity > 0 and landing > self.target_steps) or (
                    self.velocity < 0 and landing < self.target_steps
                ):
                    self.velocity = (self.target_steps - self.position) / dt
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
        limit = min(self._get16(scs.REG_TORQUE_LIMIT), self._get16(scs.REG_MAX_TORQUE))
        if not self._torque_on() or (effort == 0 and self.velocity == 0):
            self.load_permille = 0.0
            self._pushing_us = 0
            return
        if pushing_against_something:
            self.load_permille = limit if effort > 0 else -limit
            if self.load_permille and abs(self.load_permille) >= _OVERLOAD_LOAD:
                self._pushing_us += int(dt * 1e6)
                if self._pushing_us >= _OVERLOAD_US:
                    self.error_flags |= scs.FLAG_OVERLOAD
                    self.regs[scs.REG_TORQUE_ENABLE] = 0
            return
        self._pushing_us = 0
        share = 30 + 150 * abs(self.velocity) / self.max_cps  # friction grows with speed
        direction = self.velocity if self.velocity else effort
        self.load_permille = min(share, limit) if direction >= 0 else -min(share, limit)


class ScsBus(ServoBus):
    """The simulator's daisy chain, logging every well-formed packet for the tests to read."""

    def __init__(self):
        super().__init__()
        self.log = []  # (id, instruction, params) of every well-formed packet, in order

    def add(self, servo):
        self.servos[servo.servo_id] = servo  # a test may put a fresh servo in an old one's place
        return servo

    def change_id(self, old_id, new_id):
        servo = self.servos.pop(old_id)
        servo.regs[scs.REG_ID] = new_id
        self.servos[new_id] = servo

    def execute(self, servo_id, instruction, params):
        bounded.append(self.log, (servo_id, instruction, bytes(params)))
        return super().execute(servo_id, instruction, params)
