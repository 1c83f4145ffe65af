"""motor_process: the registry, dispatch and measured clock of the control tick."""

from __future__ import annotations

import random

import pytest

import openbricks_native
from openbricks_native import MotorProcess, Servo

from .plant import WheelPlant


@pytest.fixture
def process():
    return MotorProcess()


class Recorder:
    def __init__(self, log, name):
        self.log = log
        self.name = name

    def __call__(self, now_ms):
        self.log.append((self.name, now_ms))


def test_module_process_starts_idle():
    mp = openbricks_native.motor_process
    mp.reset()
    assert not mp.is_running()
    assert mp.subscribers() == []


def test_callables_are_ticked_in_subscription_order_with_the_clock(process):
    log = []
    a, b = Recorder(log, "a"), Recorder(log, "b")
    process.subscribe(a)
    process.subscribe(b)
    assert process.is_running()
    process.tick(5)
    process.tick(6)
    assert log == [("a", 5), ("b", 5), ("a", 6), ("b", 6)]
    assert process.now_ms() == 6
    assert process.tick_count == 2


def test_subscribe_is_idempotent_and_unsubscribe_tolerates_strangers(process):
    log = []
    a = Recorder(log, "a")
    process.subscribe(a)
    process.subscribe(a)
    assert process.count == 1
    process.unsubscribe(Recorder(log, "never subscribed"))
    process.unsubscribe(a)
    process.unsubscribe(a)
    process.tick(1)
    assert log == []
    assert not process.is_running()


def test_unsubscribe_keeps_the_order_of_the_others(process):
    log = []
    subs = [Recorder(log, n) for n in "abcd"]
    for s in subs:
        process.subscribe(s)
    process.unsubscribe(subs[1])
    process.tick(1)
    assert [n for n, _ in log] == ["a", "c", "d"]
    assert process.subscribers() == [subs[0], subs[2], subs[3]]


def test_capacity_is_sixteen(process):
    subs = [Recorder([], i) for i in range(16)]
    for s in subs:
        process.subscribe(s)
    with pytest.raises(RuntimeError, match="all 16 subscriber slots are taken"):
        process.subscribe(Recorder([], "one too many"))
    process.unsubscribe(subs[3])
    process.subscribe(Recorder([], "fits again"))
    assert process.count == 16


def test_a_subscriber_may_unsubscribe_itself_and_others_mid_tick(process):
    log = []
    c = Recorder(log, "c")

    def a(now_ms):
        log.append(("a", now_ms))
        process.unsubscribe(a)
        process.unsubscribe(c)

    b = Recorder(log, "b")
    for s in (a, b, c):
        process.subscribe(s)
    process.tick(1)
    process.tick(2)
    assert log == [("a", 1), ("b", 1), ("b", 2)], "c was removed before its turn; a ran once"


def test_a_failing_subscriber_does_not_stop_the_others(process):
    log = []

    def broken(now_ms):
        raise ZeroDivisionError("sensor math")

    process.subscribe(broken)
    process.subscribe(Recorder(log, "after"))
    with pytest.raises(ZeroDivisionError, match="sensor math"):
        process.tick(1)
    assert log == [("after", 1)]


def test_reset_forgets_subscribers_and_clock(process):
    process.subscribe(Recorder([], "a"))
    process.tick(100)
    process.reset()
    assert not process.is_running()
    assert process.now_ms() == 0
    assert process.tick_count == 0


def test_late_ticks_are_measured_and_the_clock_wraps(process):
    seen = []
    process.subscribe(seen.append)
    for now in (2**32 - 2, 2**32 - 1, 2**32 + 3):
        process.tick(now)
    assert seen == [2**32 - 2, 2**32 - 1, 3]
    assert process.last_dt_ms == 4
    assert process.late_ticks == 1


def test_refuses_what_it_cannot_tick(process):
    with pytest.raises(TypeError, match="expected a Servo, a DriveBase or a callable"):
        process.subscribe(42)
    with pytest.raises(ValueError, match="has no IO to tick"):
        process.subscribe(Servo())
    with pytest.raises(TypeError, match="now_ms must be an int"):
        process.tick(1.5)
    with pytest.raises(ValueError, match="now_ms must be within"):
        process.tick(-1)


class CallableWheel:
    """A plant behind the Servo's Python-callable IO, stepped by the ticks themselves."""

    def __init__(self):
        self.plant = WheelPlant()
        self.duty = None
        self.last_ms = None

    def advance_to(self, now_ms):
        if self.last_ms is not None:
            self.plant.step(self.duty, (now_ms - self.last_ms) / 1000.0)
        self.last_ms = now_ms

    def read(self):
        return self.plant.encoder_deg

    def write(self, duty):
        self.duty = duty

    def coast(self):
        self.duty = None


def run_move(tick_times_ms):
    """run_target ticked at the given times; returns when done() first held and the final angle."""
    process = MotorProcess()
    wheel = CallableWheel()
    servo = Servo(read_angle=wheel.read, write_duty=wheel.write, write_coast=wheel.coast)
    process.subscribe(servo)
    wheel.advance_to(0)
    process.tick(0)
    servo.run_target(400, 720, then="hold")
    done_at = None
    for now in tick_times_ms:
        wheel.advance_to(now)
        process.tick(now)
        if done_at is None and servo.done():
            done_at = now
    return done_at, wheel.plant.angle_deg, servo


def test_native_servo_subscriber_runs_a_move(process):
    done_at, angle, servo = run_move(range(1, 3000))
    assert done_at is not None
    assert angle == pytest.approx(720.0, abs=1.0)
    assert servo.failed_reads == 0


def test_dropped_ticks_cost_updates_not_trajectory_time():
    # The profile takes 720/400 + 400/1500 = 2.07 s. Dropping a third of the ticks at random (gaps up to
    # 5 ms) must not stretch the move: the clock is measured, so the trajectory is sampled at true time.
    regular_done, regular_angle, _ = run_move(range(1, 4000))
    rng = random.Random(7)
    irregular = [t for t in range(1, 4000) if rng.random() > 0.33 or t % 5 == 0]
    irregular_done, irregular_angle, _ = run_move(irregular)
    assert regular_done == pytest.approx(2070, abs=60)
    assert abs(irregular_done - regular_done) <= 25, (
        f"done at {irregular_done} ms with dropped ticks vs {regular_done} ms"
    )
    assert irregular_angle == pytest.approx(720.0, abs=1.0)


def test_servo_callable_errors_surface_from_tick(process):
    def bad_read():
        raise OSError("encoder unplugged")

    servo = Servo(read_angle=bad_read, write_duty=lambda d: None, write_coast=lambda: None)
    process.subscribe(servo)
    with pytest.raises(OSError, match="encoder unplugged"):
        process.tick(1)
    assert servo.failed_reads == 1
