"""A virtual hub's run limits and how the host's button press reads (its pacing: tests/sim/test_pacing.py)."""

import time

import pytest

from openbricks_sim.shim import mptime
from openbricks_sim.virtual_hub.world import (
    CLICK_HOLD_MS,
    ProgramButton,
    RunLimitExceeded,
    RunLimits,
    checked_time,
)


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


def test_the_simulated_time_limit_ends_a_sleeping_run_and_is_not_an_exception(clock):
    limits = RunLimits(clock, interrupt=None, sim_limit_ms=500)
    hub_time = checked_time(limits.check)
    limits.start()
    with pytest.raises(RunLimitExceeded, match="500 ms of simulated time") as caught:
        hub_time.sleep_us(10_000_000)
    assert not isinstance(caught.value, Exception)  # `except Exception` in a program cannot keep it
    assert clock.us <= 520_000
    limits.stop()
    hub_time.sleep(10)  # between runs nothing is limited


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
