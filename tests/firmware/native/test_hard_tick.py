"""The hard tick through the host binding: a 1 kHz timer below the interpreter (a POSIX thread on a
host, esp_timer on the hub), checked by motor_process.hard_tick_selftest() as the manual says."""

import time

import pytest

import openbricks_native


def test_the_self_test_counts_a_tick_per_millisecond_and_the_count_keeps_growing():
    process = openbricks_native.motor_process
    ticks, expected = process.hard_tick_selftest()
    assert expected in range(99, 110) and abs(ticks - expected) <= 0.1 * expected
    before = process.hard_tick_count()
    time.sleep(0.05)  # the hard tick runs whatever Python does (here: sleeps)
    assert process.hard_tick_count() - before >= 40


def test_the_hard_tick_runs_while_python_spins_without_sleeping():
    process = openbricks_native.motor_process
    process.hard_tick_selftest()  # the hard tick runs from here on
    before = process.hard_tick_count()
    deadline = time.perf_counter() + 0.05
    while time.perf_counter() < deadline:
        pass
    # On a busy host the timer thread may wait for a core, then delivers the ticks it owes (it wakes
    # on absolute deadlines): none of the 50 is lost to Python holding the interpreter.
    owed_by = time.perf_counter() + 0.2
    while process.hard_tick_count() - before < 50 and time.perf_counter() < owed_by:
        time.sleep(0.001)
    assert process.hard_tick_count() - before >= 50


def test_a_self_test_of_no_length_is_refused():
    with pytest.raises(ValueError, match="10..10000 ms"):
        openbricks_native.motor_process.hard_tick_selftest(duration_ms=0)
