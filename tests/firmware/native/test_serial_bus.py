"""The serial-bus engine (serial_bus.c) through the host binding, over an in-memory bus of scripted servos.

The wire is a Python object with the UART surface the engine's adapter uses (write, read, any); its
servos answer real SCS packets from a register file, and a test can make one go silent, answer
garbage or half a reply, or have another id answer in its place. Faults must cost a failed read,
never wedge the tick or overrun its bus budget.
"""

from hypothesis import given, settings
from hypothesis import strategies as st

import openbricks_native
from openbricks_native import scs

BUDGET_US = 1000
DEG_PER_COUNT = 360 / scs.COUNTS_PER_REV


class ScriptedServo:
    def __init__(self, servo_id):
        self.id = servo_id
        self.counts = 0
        self.speed_steps = 0
        self.load = 0
        self.mode = 0
        self.torque = None
        self.duty_raw = None
        self.fault = None  # None, "silent", "truncated", "wrong_id", or bytes to answer instead

    def status(self, params=b""):
        if self.fault == "silent":
            return b""
        if self.fault == "wrong_id":
            return scs.status(self.id + 10, 0, params)
        reply = scs.status(self.id, 0, params)
        if self.fault == "truncated":
            return reply[: len(reply) // 2]
        if isinstance(self.fault, bytes):
            return self.fault
        return reply

    def feedback(self):
        return (
            scs.encode_position(self.counts) + scs.encode_speed(self.speed_steps) + scs.encode_load(self.load)
        )

    def write(self, address, data):
        registers = {address + i: b for i, b in enumerate(data)}
        if scs.REG_MODE in registers:
            self.mode = registers[scs.REG_MODE]
        if scs.REG_TORQUE_ENABLE in registers:
            self.torque = registers[scs.REG_TORQUE_ENABLE]
        if scs.REG_GOAL_TIME in registers and scs.REG_GOAL_TIME + 1 in registers:
            self.duty_raw = registers[scs.REG_GOAL_TIME] | registers[scs.REG_GOAL_TIME + 1] << 8

    @property
    def duty_pct(self):
        raw, sign = self.duty_raw or 0, 1 << scs.DUTY_SIGN_BIT
        magnitude = raw & (sign - 1)
        return (-magnitude if raw & sign else magnitude) / 10


class ScriptedBus:
    """The UART the engine writes to: every packet is answered at once from the scripted servos."""

    def __init__(self, *ids):
        self.servos = {i: ScriptedServo(i) for i in ids}
        self._rx = b""
        self.packets = []

    def any(self):
        return len(self._rx)

    def read(self, n=None):
        if not self._rx:
            return None
        n = len(self._rx) if n is None else n
        out, self._rx = self._rx[:n], self._rx[n:]
        return out

    def write(self, data):
        frame = scs.decode_frame(bytes(data))
        assert frame.result == "ok", (data, frame)
        self.packets.append(frame)
        self._rx += self._answer(frame)
        return len(data)

    def _answer(self, frame):
        if frame.instruction == scs.SYNC_WRITE:
            address, width = frame.params[0], frame.params[1]
            rows = frame.params[2:]
            for i in range(0, len(rows), width + 1):
                servo = self.servos.get(rows[i])
                if servo is not None and servo.fault != "silent":
                    servo.write(address, rows[i + 1 : i + 1 + width])
            return b""
        servo = self.servos.get(frame.id)
        if servo is None:
            return b""
        if frame.instruction == scs.READ:
            address, length = frame.params
            assert (address, length) == (scs.REG_PRESENT_POSITION, 6)
            return servo.status(servo.feedback())
        if frame.instruction == scs.WRITE:
            if servo.fault != "silent":
                servo.write(frame.params[0], frame.params[1:])
            return servo.status()
        return servo.status()


def engine_over(*ids):
    openbricks_native.motor_process.reset()  # an engine subscribes itself when it adopts a servo
    bus = ScriptedBus(*ids)
    return openbricks_native.SerialBus(bus), bus


def ticks(engine, n, start=0):
    for t in range(start, start + n):
        engine.tick(t)


def test_adoption_takes_the_servo_to_coasting_duty_mode_with_a_first_reading():
    engine, bus = engine_over(1)
    bus.servos[1].counts = 400
    slot = engine.adopt(1)
    assert slot == 0
    servo = bus.servos[1]
    assert (servo.mode, servo.torque) == (scs.MODE_DUTY, 0)
    assert engine.angle_deg(slot) == 0.0  # angles count from where the wheel was adopted
    assert engine.stats(slot) == (1, 0, 0)


def test_a_tick_sync_writes_the_duties_and_reads_every_wheel_in_its_users_frame():
    engine, bus = engine_over(1, 2)
    left, right = engine.adopt(1), engine.adopt(2, invert=True)
    engine.motor_io(left).write_duty(40)
    engine.motor_io(right).write_duty(40)
    bus.servos[1].counts += 1024
    bus.servos[2].counts -= 1024
    bus.servos[2].speed_steps = -500
    engine.tick(0)
    assert bus.servos[1].duty_pct == 40 and bus.servos[2].duty_pct == -40  # the mirrored one backwards
    assert bus.servos[1].torque == 1 and bus.servos[2].torque == 1
    assert engine.angle_deg(left) == 90 and engine.angle_deg(right) == 90
    assert abs(engine.speed_dps(right) - 500 * DEG_PER_COUNT) < 1e-3
    assert engine.motor_io(right).read_angle() == 90
    engine.motor_io(left).coast()
    engine.tick(1)
    assert bus.servos[1].torque == 0


def test_multi_turn_positions_unwrap_across_the_registers_window():
    engine, bus = engine_over(1)
    bus.servos[1].counts = 32000
    slot = engine.adopt(1)
    for step in range(20):
        bus.servos[1].counts = (32000 + 100 * (step + 1) + 32767) % 65535 - 32767  # wraps at +-32767
        engine.tick(step)
    assert abs(engine.angle_deg(slot) - 2000 * DEG_PER_COUNT) < 1e-3


def test_two_wheels_cost_well_under_the_1ms_budget_at_1_mbaud():
    engine, _bus = engine_over(1, 2)
    for servo_id in (1, 2):
        engine.motor_io(engine.adopt(servo_id)).write_duty(10)
    ticks(engine, 10)
    assert engine.bus_stats()["last_tick_bus_us"] < 600  # two 20-byte reads and a 14-byte sync write


def test_a_servo_that_does_not_answer_is_not_adopted():
    engine, bus = engine_over(1)
    bus.servos[1].fault = "silent"
    try:
        engine.adopt(1)
    except OSError as err:
        assert "not responding on the bus: servo id 1" in str(err)
    else:
        raise AssertionError("adopting a silent servo did not raise")


def test_a_silent_servo_is_counted_and_reads_as_unavailable_after_three_misses():
    engine, bus = engine_over(1, 2)
    left, right = engine.adopt(1), engine.adopt(2)
    bus.servos[2].fault = "silent"
    engine.tick(0)
    assert engine.angle_deg(right) is not None  # one miss is a glitch...
    assert engine.motor_io(right).read_angle() is None  # ...but no fresh reading for the controller
    ticks(engine, 3, 1)
    replies, failed, in_a_row = engine.stats(right)
    assert in_a_row >= 3 and failed >= 3
    assert (
        engine.angle_deg(right) is None and engine.speed_dps(right) is None and engine.load_pct(right) is None
    )
    assert engine.angle_deg(left) is not None  # the other wheel is still read
    bus.servos[2].fault = None
    engine.tick(10)
    assert engine.angle_deg(right) is not None and engine.stats(right)[2] == 0


def test_another_id_answering_is_not_taken_for_the_servo():
    engine, bus = engine_over(1)
    slot = engine.adopt(1)
    bus.servos[1].counts = 2048
    bus.servos[1].fault = "wrong_id"
    ticks(engine, 3)
    assert engine.angle_deg(slot) is None
    assert engine.bus_stats()["garbage_frames"] >= 3


@settings(max_examples=200, deadline=None)
@given(
    replies=st.lists(
        st.binary(max_size=40) | st.sampled_from(["truncated", "wrong_id", "silent"]), min_size=1, max_size=12
    )
)
def test_garbage_and_truncated_replies_never_wedge_the_engine(replies):
    engine, bus = engine_over(1, 2)
    slots = engine.adopt(1), engine.adopt(2)
    for t, fault in enumerate(replies):
        bus.servos[2].fault = fault
        engine.tick(t)
        # Every tick ends within its budget, whatever came back.
        assert engine.bus_stats()["last_tick_bus_us"] <= BUDGET_US
    bus.servos[2].fault = None
    bus.servos[2].counts += 4096
    engine.tick(len(replies))
    engine.tick(len(replies) + 1)
    assert engine.stats(slots[1])[2] == 0  # answering again: the next read is taken
    assert engine.angle_deg(slots[0]) == 0.0


def test_bad_slots_and_ids_are_refused_clearly():
    engine, _bus = engine_over(1)
    for bad in (0, -1, "0", None):
        try:
            engine.angle_deg(bad)
        except ValueError as err:
            assert "is not an adopted servo" in str(err)
        else:
            raise AssertionError(f"slot {bad!r} was accepted")
    try:
        engine.adopt(254)
    except ValueError as err:
        assert "0..253" in str(err)
    else:
        raise AssertionError("adopting the broadcast id was accepted")
