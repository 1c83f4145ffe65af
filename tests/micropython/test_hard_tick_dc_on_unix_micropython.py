"""The hard tick runs a DC drive base's whole loop in C while the program's Python is busy.

On the unix MicroPython with the real `_openbricks_native` (`make micropython`), the runtime's
DriveBase over two JGB37Motors (hard_tick_dc_drive.py) drives the firmware's H-bridge core and
reads the PCNT encoder core, here wired to emulated DC gear motors in C (`_openbricks_bench`) where
the hub has GPIO, LEDC and PCNT units. Its motor IO is joined in C, so the controller is hard-safe:
the program spins in Python loops that never sleep, and every control tick of the busy stretch comes
from the hard tick, which reads the encoders and writes the bridges itself; the moves land.
"""

from pathlib import Path

import pytest

from .test_hard_tick_on_unix_micropython import run_script
from .test_runtime_on_unix_micropython import unix_micropython  # noqa: F401 - the fixture

SCRIPT = Path(__file__).resolve().parent / "hard_tick_dc_drive.py"

pytestmark = pytest.mark.micropython


@pytest.fixture(scope="module")
def measured(unix_micropython):  # noqa: F811 - the fixture imported above
    return run_script(unix_micropython, SCRIPT)


def test_a_dc_straight_lands_within_2_mm_while_python_spins_without_sleeping(measured):
    straight = measured["straight"]
    assert straight["busy_rounds"] > 0
    assert straight["done"], straight
    assert abs(straight["left_mm"] - 300) < 2 and abs(straight["right_mm"] - 300) < 2, straight
    assert abs(straight["distance_mm"] - 300) < 2, straight


def test_the_dc_drive_base_runs_on_the_hard_tick_reading_encoders_and_writing_bridges_in_c(measured):
    straight = measured["straight"]
    assert straight["ticks_itself"] is True, straight  # every subscriber is native: no Python in the loop
    # 4.5 s at 1 kHz; a loaded host's timer thread may lose a few periods, never Python's doing.
    assert straight["control_ticks"] >= 4000, straight
    assert straight["control_ticks"] <= straight["hard_ticks"], straight
    # Both encoders read every period (the tick's poll and the controller's read), both bridges driven.
    assert straight["encoder_reads"] >= 2 * straight["control_ticks"], straight
    assert straight["bridge_writes"] >= 100, straight
    assert straight["levels"] == [[False, False, 0], [False, False, 0]], straight  # then="coast"


def test_a_dc_turn_lands_while_python_spins(measured):
    turn = measured["turn"]
    assert turn["done"], turn
    assert abs(turn["angle_deg"] - 90) < 1, turn
    arc_mm = 90 / 360 * 3.141592653589793 * 150
    assert abs(turn["left_mm"] - arc_mm) < 2 and abs(turn["right_mm"] + arc_mm) < 2, turn


def test_a_direct_dc_command_drives_the_same_bridge_after_the_drive_base(measured):
    direct = measured["direct"]
    assert direct["levels"] == [True, False, round(0.4 * 65536)], direct  # forward at 40 % of EN
    assert direct["speed_dps"] == pytest.approx(0.4 * 1230, rel=0.05), direct
