"""How time passes on a virtual hub (pacing, run limits) and how the host's button press reads."""

import threading
import time

import pytest

from openbricks_sim.shim import mptime
from openbricks_sim.virtual_hub.world import CLICK_HOLD_MS, Pacer, ProgramButton, RunLimitExceeded, RunLimits


class Clock:
    """The part of SimClock the pacer and button use: time moves only when advanced."""

    def __init__(self):
        self.us = 0

    def now_us(self):
        return self.us

    def advance_us(self, us):
        self.us += us


@pytest.fixture
def clock():
    fake = Clock()
    mptime.bind(fake)
    try:
        yield fake
    finally:
        mptime.bind(None)


def test_a_click_holds_the_button_long_enough_for_the_debounce_then_lets_go(clock):
    button = ProgramButton(clock)
    assert button.level() == 1
    button.click()
    button.click()
    assert button.level() == 0
    clock.advance_us((CLICK_HOLD_MS - 1) * 1000)
    assert button.level() == 0
    clock.advance_us(1000)
    assert button.level() == 1  # released, and kept up before the queued second click
    clock.advance_us((CLICK_HOLD_MS - 1) * 1000)
    assert button.level() == 1
    clock.advance_us(1000)
    assert button.level() == 0
    assert button.pending_clicks == 1


def test_press_and_release_hold_the_level_until_told(clock):
    button = ProgramButton(clock)
    button.press()
    clock.advance_us(10_000_000)
    assert button.level() == 0
    button.release()
    assert button.level() == 1


def test_real_time_pacing_makes_a_sleep_take_wall_time(clock):
    pacer = Pacer(clock, lambda: 1.0, threading.Event())
    started = time.perf_counter()
    pacer.sleep_us(300_000)
    assert 0.25 < time.perf_counter() - started < 1.0
    assert clock.us == 300_000


def test_an_unpaced_run_goes_as_fast_as_the_cpu_allows(clock):
    pacer = Pacer(clock, lambda: None, threading.Event())
    started = time.perf_counter()
    pacer.sleep_us(60_000_000)
    assert time.perf_counter() - started < 1.0 and clock.us == 60_000_000


def test_time_spent_waiting_for_the_host_is_not_raced_through_afterwards(clock):
    pacer = Pacer(clock, lambda: 1.0, threading.Event())
    pacer.sleep_us(40_000)
    time.sleep(0.5)  # the hub sat at its prompt: no simulated time passed
    started = time.perf_counter()
    pacer.sleep_us(200_000)
    assert time.perf_counter() - started > 0.15


def test_an_interrupt_cuts_a_paced_wait_short(clock):
    wakeup = threading.Event()
    pacer = Pacer(clock, lambda: 0.01, wakeup)  # 100 times slower than real time
    pacer.sleep_us(1000)
    wakeup.set()
    started = time.perf_counter()
    pacer.sleep_us(20_000)  # 2 s of wall time unless woken
    assert time.perf_counter() - started < 0.5


def test_the_simulated_time_limit_ends_a_run_and_is_not_an_exception(clock):
    limits = RunLimits(clock, interrupt=None, sim_limit_ms=500)
    pacer = Pacer(clock, lambda: None, threading.Event(), limits.check)
    limits.start()
    with pytest.raises(RunLimitExceeded, match="500 ms of simulated time") as caught:
        pacer.sleep_us(10_000_000)
    assert not isinstance(caught.value, Exception)  # `except Exception` in a program cannot keep it
    assert clock.us <= 520_000
    limits.stop()
    pacer.sleep_us(10_000_000)  # between runs nothing is limited


def test_the_wall_clock_limit_interrupts_until_the_run_ends(clock):
    raised = []
    limits = RunLimits(clock, interrupt=raised.append, wall_limit_s=0.1)
    limits.start()
    time.sleep(0.3)
    limits.stop()
    assert raised and "wall-clock limit of 0.1 s" in str(raised[0]())
    count = len(raised)
    time.sleep(1.2)
    assert len(raised) == count
