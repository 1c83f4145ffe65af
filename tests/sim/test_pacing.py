"""The one pacer (sim run --speed, the viewer, a virtual hub): simulated time follows the wall clock at
the chosen speed, stands still while paused, and a change of speed, a stop or an interrupt takes effect
at once, even mid-wait.

The simulated robot stands idle; what is measured is how long advancing its clock takes in wall time,
which is what a person watching the run experiences."""

import threading
import time

import pytest

from openbricks_sim.pacing import Pacer
from openbricks_sim.simulation import Simulation


@pytest.fixture
def sim():
    simulation = Simulation("empty", "st3032", epoch_ms=0)
    assert simulation.physics.model  # built now: these pace real physics steps, not a clock alone
    yield simulation
    simulation.close()


def wall_time_to_advance(clock, ms):
    start = time.perf_counter()
    clock.advance_us(ms * 1000)
    return time.perf_counter() - start


class FrameCounter:
    def __init__(self):
        self.count = 0

    def __call__(self):
        self.count += 1


def advance_in_background(clock, ms):
    """Advance the clock on another thread (as a program would); returns the thread."""
    thread = threading.Thread(target=clock.advance_us, args=(ms * 1000,), daemon=True)
    thread.start()
    return thread


@pytest.mark.parametrize("speed", [0.5, 2.0, 4.0])
def test_simulated_time_follows_the_wall_clock_at_the_chosen_speed(sim, speed):
    pacer = Pacer(sim.clock, FrameCounter(), speed=speed)
    pacer.start()
    wall_s = wall_time_to_advance(sim.clock, 1000)
    assert wall_s == pytest.approx(1.0 / speed, rel=0.15, abs=0.03)


def test_as_fast_as_possible_never_waits(sim):
    pacer = Pacer(sim.clock, FrameCounter(), speed=None)
    pacer.start()
    wall_s = wall_time_to_advance(sim.clock, 5000)
    assert wall_s < 1.0, f"5 s of an idle robot took {wall_s:.2f} s: something waited"


@pytest.mark.parametrize("speed", [0.25, 1.0, 8.0, None])
def test_the_viewer_gets_about_frame_hz_frames_whatever_the_speed(sim, speed):
    frames = FrameCounter()
    pacer = Pacer(sim.clock, frames, speed=speed, frame_hz=60)
    pacer.start()
    # Advance for about a second of wall time at this speed (as fast as possible: 20 s simulated).
    ms = 20_000 if speed is None else round(1000 * speed)
    wall_s = wall_time_to_advance(sim.clock, ms)
    rate = frames.count / wall_s
    assert 30 <= rate <= 90, f"{frames.count} frames in {wall_s:.2f} s at speed {speed}"


def test_pause_stops_simulated_time_and_resume_goes_on_from_there(sim):
    pacer = Pacer(sim.clock, FrameCounter(), speed=1.0)
    pacer.start()
    thread = advance_in_background(sim.clock, 2000)
    time.sleep(0.3)
    pacer.paused = True
    time.sleep(0.1)  # the pause lands at the next frame
    held_at = sim.clock.now_ms()
    time.sleep(0.6)
    assert sim.clock.now_ms() == held_at, "simulated time moved while paused"
    assert thread.is_alive()
    pacer.paused = False
    thread.join(timeout=5.0)
    assert not thread.is_alive()
    assert sim.clock.now_ms() == 2000


def test_a_new_speed_applies_at_once_even_in_the_middle_of_a_wait(sim):
    pacer = Pacer(sim.clock, FrameCounter(), speed=0.1)  # 60 s of simulated time would take 10 min
    pacer.start()
    thread = advance_in_background(sim.clock, 60_000)
    time.sleep(0.3)
    switched = time.perf_counter()
    pacer.speed = None
    thread.join(timeout=10.0)
    assert not thread.is_alive()
    assert time.perf_counter() - switched < 3.0


def test_slowing_down_mid_run_paces_from_the_change_not_from_the_start(sim):
    pacer = Pacer(sim.clock, FrameCounter(), speed=None)
    pacer.start()
    sim.clock.advance_us(5_000_000)  # 5 s simulated in a blink
    pacer.speed = 2.0
    # Measured from the run's start, 5.5 s simulated at 2x would be "due" 2.75 s in: far behind, so a
    # pacer anchored at the start would not wait at all.
    assert wall_time_to_advance(sim.clock, 500) == pytest.approx(0.25, abs=0.08)


def test_stop_releases_a_paused_run(sim):
    pacer = Pacer(sim.clock, FrameCounter(), speed=1.0)
    pacer.start()
    pacer.paused = True
    thread = advance_in_background(sim.clock, 500)
    time.sleep(0.3)
    assert thread.is_alive()
    pacer.stop()
    thread.join(timeout=5.0)
    assert not thread.is_alive() and sim.clock.now_ms() == 500


def test_a_simulation_built_with_a_speed_paces_itself_and_one_pacer_replaces_another():
    simulation = Simulation("empty", "st3032", speed=4.0)
    try:
        assert wall_time_to_advance(simulation.clock, 1000) == pytest.approx(0.25, rel=0.15, abs=0.03)
        first = simulation.pacer
        simulation.pace(None)  # the viewer takes over: the first pacer must not hold time any more
        assert simulation.pacer is not first
        assert wall_time_to_advance(simulation.clock, 5000) < 1.0
    finally:
        simulation.close()


def test_an_unpaced_simulation_has_no_pacer(sim):
    assert sim.pacer is None  # nothing then depends on the wall clock: a job repeats exactly


def test_time_spent_not_advancing_the_clock_is_not_raced_through_afterwards(sim):
    pacer = Pacer(sim.clock, speed=1.0)
    pacer.start()
    sim.clock.advance_us(40_000)
    time.sleep(0.5)  # a virtual hub sat at its prompt: no simulated time passed
    assert wall_time_to_advance(sim.clock, 200) > 0.15


def test_an_interrupt_on_its_way_cuts_a_paced_wait_short(sim):
    wakeup = threading.Event()
    pacer = Pacer(sim.clock, speed=0.01, wakeup=wakeup)  # 100 times slower than real time
    pacer.start()
    sim.clock.advance_us(1000)
    thread = advance_in_background(sim.clock, 20)  # 2 s of wall time unless woken
    time.sleep(0.1)
    started = time.perf_counter()
    wakeup.set()
    pacer.nudge()
    thread.join(timeout=5.0)
    assert not thread.is_alive() and time.perf_counter() - started < 0.5


def test_pacing_goes_on_after_an_interrupt_raised_while_held(sim):
    """A host's Ctrl-C reaches a virtual hub's program while the pacer holds it: the program ends,
    and the hub's clock must still follow the wall clock afterwards, not run flat out."""

    class Interrupted(Exception):
        pass

    frames = []

    def interrupt_once():
        frames.append(time.perf_counter())
        if len(frames) == 2:
            raise Interrupted

    pacer = Pacer(sim.clock, interrupt_once, speed=1.0)
    pacer.start()
    with pytest.raises(Interrupted):
        sim.clock.advance_us(1_000_000)
    assert wall_time_to_advance(sim.clock, 500) == pytest.approx(0.5, rel=0.15, abs=0.03)


def test_time_the_simulation_could_not_keep_up_with_is_reported(sim):
    behind = []
    pacer = Pacer(sim.clock, speed=1.0, on_behind=behind.append)
    pacer.start()
    sim.clock.advance_us(40_000)
    time.sleep(0.5)  # the program's thread got no CPU: simulated time fell behind the wall clock
    sim.clock.advance_us(40_000)
    assert len(behind) == 1 and 0.4 < behind[0] < 0.7


def test_a_speed_that_is_not_a_positive_number_is_refused(sim):
    pacer = Pacer(sim.clock, FrameCounter())
    with pytest.raises(ValueError, match="positive real-time factor"):
        pacer.speed = 0
