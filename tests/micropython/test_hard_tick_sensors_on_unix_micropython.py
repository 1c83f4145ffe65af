"""The hard tick reads the sensors while the program's Python is busy (hard_tick_sensors.py).

On the unix MicroPython with the real `_openbricks_native` (`make micropython`), sensors on native
links (emulated hardware in C from `_openbricks_bench`, standing where the hub's PCNT unit and SPI
bus are) are polled by the 1 kHz hard tick (a host thread here, esp_timer on the hub), with no
Python call: a PCNT encoder whose counter wraps five times keeps its exact count although the
program never reads it, and a drive base steering by the ICM-45686 stays on the hard tick and lands
its turn on the body's true heading while the tyres scrub.
"""

from pathlib import Path

import pytest

from .test_hard_tick_on_unix_micropython import run_script
from .test_runtime_on_unix_micropython import unix_micropython  # noqa: F401 - the fixture

SCRIPT = Path(__file__).resolve().parent / "hard_tick_sensors.py"
MG370_CPR = 68028

pytestmark = pytest.mark.micropython


@pytest.fixture(scope="module")
def measured(unix_micropython):  # noqa: F811 - the fixture imported above
    return run_script(unix_micropython, SCRIPT)


def test_an_encoder_nobody_reads_keeps_its_exact_count_across_counter_wraps(measured):
    enc = measured["encoder"]
    assert enc["busy_rounds"] > 0
    assert enc["true_count"] > 2 * 32767, enc  # the PCNT counter wrapped twice meanwhile
    assert enc["count"] == enc["true_count"], enc
    assert enc["turns"] == pytest.approx(enc["true_count"] / MG370_CPR), enc


def test_the_hard_tick_read_the_counter_and_stops_when_it_is_closed(measured):
    enc = measured["encoder"]
    assert enc["hard_reads"] >= 1000, enc  # 3 s at 1 kHz; a loaded host's timer thread loses some
    assert enc["reads_after_close"] == 0, enc


def test_a_gyro_turn_lands_on_the_true_heading_while_python_spins(measured):
    gyro = measured["gyro"]
    assert gyro["calibrated"], gyro  # the bias locked from hard-tick samples at rest
    assert gyro["busy_rounds"] > 0
    assert gyro["done"], gyro
    assert gyro["angle_deg"] == pytest.approx(90, abs=0.5), gyro
    # The tyres scrub: steering by the encoders would have turned the body 81 degrees. A loaded
    # host's timer thread may stall longer than the integrator bridges (100 ms); the rotation during
    # such a stall is what no gyro could see (the hub's esp_timer does not stall), so it is set apart.
    seen_deg = gyro["true_turn_deg"] - gyro["unseen_deg"]
    assert seen_deg == pytest.approx(90, abs=3.0), gyro


def test_the_gyro_drive_base_stays_on_the_hard_tick_with_a_fresh_burst_each_period(measured):
    gyro = measured["gyro"]
    assert gyro["ticks_itself"] is True, gyro  # every subscriber, the heading source included, is native
    assert gyro["control_ticks"] >= 1000, gyro
    assert gyro["control_ticks"] <= gyro["hard_ticks"], gyro
    assert gyro["imu_bursts"] >= gyro["control_ticks"], gyro
    reads_ok, read_errors, configured = gyro["imu_stats"]
    assert configured and read_errors == 0, gyro
