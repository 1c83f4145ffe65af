"""The simulated clock: Python timers fire at their due times while the physics follows in whole
milliseconds, one physics call per stretch between due times.

Each test runs twice: with the clock stepping the physics through its timer queue, and with it
following the built physics' controller directly when nothing is due (SimClock.follow), which is
how a simulation runs once its physics is built. Both must give the same times and steps."""

import threading

import pytest

from openbricks_sim.clock import SimClock, SimStopped, SimTimeLimit


class RecordingPhysics:
    """Stands in for Physics: counts steps and remembers every step(n) call."""

    def __init__(self):
        self.now_ms = 0
        self.calls = []

    def step(self, n):
        self.calls.append(n)
        self.now_ms += n


@pytest.fixture(params=["through the queue", "following the controller"])
def new_clock(request):
    """SimClock(physics, ...), following `physics` as its controller in the second run."""

    def make(physics, **options):
        clock = SimClock(physics, **options)
        if request.param == "following the controller":
            clock.follow(physics)  # RecordingPhysics has the controller's now_ms and step(n)
        return clock

    return make


def test_periodic_timer_fires_at_each_due_time_with_the_physics_already_there(new_clock):
    physics = RecordingPhysics()
    clock = new_clock(physics)
    seen = []
    clock.schedule(lambda: seen.append((clock.now_us(), physics.now_ms)), 10_000, 10_000)
    clock.advance_us(35_000)
    assert seen == [(10_000, 10), (20_000, 20), (30_000, 30)]
    assert physics.calls == [10, 10, 10, 5], "one physics call per stretch between due times"
    assert clock.now_us() == 35_000


def test_a_long_sleep_with_nothing_due_is_one_physics_call(new_clock):
    physics = RecordingPhysics()
    clock = new_clock(physics)
    clock.advance_us(10_000_000)
    assert physics.calls == [10_000]


def test_sub_millisecond_sleeps_add_up_and_the_physics_follows_whole_milliseconds(new_clock):
    physics = RecordingPhysics()
    clock = new_clock(physics)
    for _ in range(3):
        clock.advance_us(400)
    assert clock.now_us() == 1200
    assert physics.now_ms == 1  # the state at t = 1 ms; the next step completes at 2 ms
    clock.advance_us(800)
    assert physics.now_ms == 2


def test_one_shot_timer_fires_once_and_a_cancelled_one_never(new_clock):
    physics = RecordingPhysics()
    clock = new_clock(physics)
    fired = []
    clock.schedule(lambda: fired.append("once"), 5_000)
    cancelled = clock.schedule(lambda: fired.append("cancelled"), 6_000, 1_000)
    cancelled.cancel()
    clock.advance_us(50_000)
    assert fired == ["once"]


def test_a_timer_callback_that_sleeps_moves_time_on_without_nesting_timers(new_clock):
    physics = RecordingPhysics()
    clock = new_clock(physics)
    order = []

    def slow():
        order.append(("slow starts", clock.now_us()))
        clock.advance_us(5_000)  # a callback that blocks for 5 ms
        order.append(("slow ends", clock.now_us()))

    clock.schedule(slow, 1_000)
    clock.schedule(lambda: order.append(("quick", clock.now_us())), 2_000)
    clock.advance_us(10_000)
    # The quick timer came due while slow() ran; it runs after slow() returns, late, as on a hub.
    assert order == [("slow starts", 1_000), ("slow ends", 6_000), ("quick", 6_000)]
    assert clock.now_us() == 10_000 and physics.now_ms == 10


def test_time_limit_stops_the_physics_exactly_at_the_limit(new_clock):
    physics = RecordingPhysics()
    clock = new_clock(physics, limit_ms=250)
    clock.advance_us(200_000)
    with pytest.raises(SimTimeLimit, match="250 ms"):
        clock.advance_us(100_000)
    assert physics.now_ms == 250 and clock.now_ms() == 250


def test_stop_requested_from_another_thread_ends_the_next_sleep(new_clock):
    clock = new_clock(RecordingPhysics())
    thread = threading.Thread(target=clock.request_stop)
    thread.start()
    thread.join()
    with pytest.raises(SimStopped):
        clock.advance_us(1_000)
    clock.advance_us(1_000)  # the request is consumed: the next sleep runs normally


def test_rtc_follows_simulated_time_and_can_be_set(new_clock):
    clock = new_clock(RecordingPhysics(), epoch_ms=1_700_000_000_000)
    clock.advance_us(1_500_000)
    assert clock.epoch_us() == 1_700_000_001_500_000
    clock.set_epoch_ms(1_800_000_000_000)
    clock.advance_us(1_000)
    assert clock.epoch_us() == 1_800_000_000_001_000


def test_cpu_charges_add_up_and_a_charge_over_a_millisecond_steps_the_physics(new_clock):
    physics = RecordingPhysics()
    clock = new_clock(physics)
    fired = []
    clock.schedule(lambda: fired.append(clock.now_us()), 1_500)
    for _ in range(499):
        clock.charge_cpu_us(2)  # a ticks_ms() read each
    assert clock.now_us() == 998 and physics.calls == [] and fired == []
    clock.charge_cpu_us(2)
    assert clock.now_us() == 1_000 and physics.now_ms == 1
    clock.charge_cpu_us(600)
    assert fired == [1_500] and clock.now_us() == 1_600 and physics.now_ms == 1


def test_a_stop_reaches_a_program_that_only_reads_the_clock(new_clock):
    clock = new_clock(RecordingPhysics())
    clock.request_stop()
    with pytest.raises(SimStopped):
        clock.charge_cpu_us(2)
