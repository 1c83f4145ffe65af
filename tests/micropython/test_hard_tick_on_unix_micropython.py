"""The hard tick runs the drive base and the bus engine in C while the program's Python is busy.

On the unix MicroPython with the real `_openbricks_native` (`make micropython`), the runtime's
DriveBase over two ST-3032s adopts them onto the C bus engine over an in-memory wire of emulated
servos (`_openbricks_bench`), and the program then spins in Python loops that never sleep
(hard_tick_drive.py). On a hub the hard tick keeps controlling the wheels meanwhile (manual,
chapter 8: the serial-bus motor path runs inside the hard tick, immune to Python stalls); so must
this build: every control tick of the busy stretch comes from the hard tick, and the moves land.
"""

import json
import subprocess
from pathlib import Path

import pytest

from .test_runtime_on_unix_micropython import unix_micropython  # noqa: F401 - the fixture

REPO = Path(__file__).resolve().parents[2]
SCRIPT = Path(__file__).resolve().parent / "hard_tick_drive.py"

pytestmark = pytest.mark.micropython


def run_script(interpreter, script):
    """Run a hard-tick script on the unix MicroPython; what its `@result {json}` line measured."""
    proc = subprocess.run(
        [str(interpreter), "-X", "heapsize=8M", str(script)],
        cwd=REPO,
        capture_output=True,
        text=True,
        timeout=120,
    )
    lines = [line for line in proc.stdout.splitlines() if line.startswith("@result ")]
    output = f"exit {proc.returncode}\n{proc.stdout[-3000:]}{proc.stderr[-3000:]}"
    assert proc.returncode == 0 and lines, output
    return json.loads(lines[-1][len("@result ") :])


@pytest.fixture(scope="module")
def measured(unix_micropython):  # noqa: F811 - the fixture imported above
    return run_script(unix_micropython, SCRIPT)


def test_a_straight_lands_while_python_spins_without_sleeping(measured):
    straight = measured["straight"]
    assert straight["busy_rounds"] > 0
    assert straight["done"], straight
    assert abs(straight["left_mm"] - 300) < 2 and abs(straight["right_mm"] - 300) < 2, straight
    assert abs(straight["distance_mm"] - 300) < 2, straight


def test_every_control_tick_of_the_busy_stretch_came_from_the_hard_tick(measured):
    straight = measured["straight"]
    # 4.5 s at 1 kHz; a loaded host's timer thread may lose a few periods, never Python's doing.
    assert straight["control_ticks"] >= 4000, straight
    assert straight["control_ticks"] <= straight["hard_ticks"], straight
    assert straight["bus_ticks"] == straight["control_ticks"], straight


def test_a_turn_lands_while_python_spins(measured):
    turn = measured["turn"]
    assert turn["done"], turn
    assert abs(turn["angle_deg"] - 90) < 1, turn
    arc_mm = 90 / 360 * 3.141592653589793 * 120
    assert abs(turn["left_mm"] - arc_mm) < 2 and abs(turn["right_mm"] + arc_mm) < 2, turn


def test_the_self_test_passes_while_the_hard_tick_runs_the_controllers(measured):
    ticks, expected = measured["selftest"]
    assert abs(ticks - expected) <= expected * 0.1
