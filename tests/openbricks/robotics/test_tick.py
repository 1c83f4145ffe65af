"""The 1 kHz motor_process tick: started where nothing else ticks the scheduler, never doubled."""

import sys
import time

import _openbricks_native

from openbricks.robotics import tick

NEEDS_NATIVE = True


def _ticks_during(ms):
    before = _openbricks_native.motor_process.tick_count
    time.sleep_ms(ms)
    return _openbricks_native.motor_process.tick_count - before


def test_a_host_without_a_native_tick_gets_a_1khz_timer_tick_with_the_real_clock():
    _openbricks_native.motor_process.reset()
    assert _ticks_during(20) == 0
    assert tick.ensure_running()
    assert 99 <= _ticks_during(100) <= 101
    assert _openbricks_native.motor_process.now_ms() == time.ticks_ms()


def test_asking_again_leaves_the_running_tick_alone():
    _openbricks_native.motor_process.reset()
    tick.ensure_running()
    assert not tick.ensure_running()
    assert not tick.ensure_running()
    assert 99 <= _ticks_during(100) <= 101  # not 200 or 300: one tick per millisecond


class _SelfTickingCores:
    """`_openbricks_native` as the simulator's and the firmware's modules have it: ticks_itself = True."""

    ticks_itself = True
    motor_process = _openbricks_native.motor_process


def test_a_runtime_that_ticks_motor_process_itself_gets_no_second_tick():
    _openbricks_native.motor_process.reset()
    sys.modules["_openbricks_native"] = _SelfTickingCores()
    try:
        assert not tick.ensure_running()
    finally:
        sys.modules["_openbricks_native"] = _openbricks_native
    assert _ticks_during(50) == 0  # (nothing below Python ticks it in this test process)


def test_the_hard_tick_below_python_passes_its_self_test():
    # Real time, not the test clock: the hard tick is the platform's 1 kHz timer (a thread on a host).
    ticks, expected = _openbricks_native.motor_process.hard_tick_selftest(duration_ms=50)
    assert abs(ticks - expected) <= expected // 10
    assert _openbricks_native.motor_process.hard_tick_count() >= ticks
