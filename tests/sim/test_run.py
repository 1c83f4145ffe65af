"""Running a program file against a world: how it ends, what it printed, where the robot got to."""

import json
import os
import signal
import subprocess
import sys

import pytest

from openbricks_sim.run import ERROR, FINISHED, MEMORY_LIMIT, STOPPED, TIME_LIMIT, WALL_LIMIT, run_program

DRIVE_FORWARD = """\
import time
from openbricks.drivers.st3032 import ST3032Motor

left = ST3032Motor(1)
right = ST3032Motor(2, invert=True)
left.run_speed(360)
right.run_speed(360)
time.sleep_ms(2000)
left.brake()
right.brake()
time.sleep_ms(300)
print("done at", time.ticks_ms())
"""


def run(source, **kwargs):
    return run_program("mission.py", source=source, **kwargs)


def test_a_program_runs_to_its_end_and_the_robot_moved():
    result = run(DRIVE_FORWARD)
    assert result.exit == FINISHED, result.error
    assert result.output.startswith("done at 23")
    assert 2300 <= result.sim_ms < 2400
    assert result.pose["x_mm"] > 500 and abs(result.pose["heading_deg"]) < 1.5
    assert result.job["world"] == "empty" and result.job["chassis"] == "st3032"


def test_an_exception_ends_the_run_with_the_programs_traceback():
    result = run("import time\ntime.sleep_ms(10)\nraise ValueError('bad mission')\n")
    assert result.exit == ERROR
    assert 'File "mission.py", line 3' in result.error and "ValueError: bad mission" in result.error
    assert result.sim_ms == 10


def test_a_traceback_shows_the_programs_frames_only_as_on_a_hub():
    source = "from openbricks.tools import plot\n\ndef build():\n    plot('speed', float('nan'))\n\nbuild()\n"
    result = run(source)
    assert result.exit == ERROR
    assert result.error == (
        "Traceback (most recent call last):\n"
        '  File "mission.py", line 6, in <module>\n'
        '  File "mission.py", line 4, in build\n'
        "ValueError: plot() value must be finite, got nan\n"
    )


def test_the_simulated_time_limit_ends_an_endless_program_exactly():
    result = run("import time\nwhile True:\n    time.sleep_ms(100)\n", limit_ms=550)
    assert result.exit == TIME_LIMIT and result.sim_ms == 550


def test_a_program_that_catches_everything_still_cannot_outlive_the_limit():
    source = """\
import time
while True:
    try:
        time.sleep_ms(100)
    except Exception:
        pass
"""
    assert run(source, limit_ms=300).exit == TIME_LIMIT


def test_a_loop_that_never_lets_time_pass_hits_the_wall_limit_with_an_explanation():
    result = run("x = 0\nwhile True:\n    x += 1\n", wall_limit_s=0.3)
    assert result.exit == WALL_LIMIT
    assert "time.sleep_ms" in result.error


def test_the_wall_limit_holds_in_a_process_started_with_sigint_ignored():
    """A background job of a script inherits SIGINT ignored; the watchdog must still end the loop."""
    previous = signal.signal(signal.SIGINT, signal.SIG_IGN)
    try:
        result = run("x = 0\nwhile True:\n    x += 1\n", wall_limit_s=0.3)
        assert signal.getsignal(signal.SIGINT) is signal.SIG_IGN  # the run leaves it as it found it
    finally:
        signal.signal(signal.SIGINT, previous)
    assert result.exit == WALL_LIMIT


def test_sys_exit_is_a_normal_end_and_machine_reset_is_reported():
    assert run("import sys\nsys.exit()\n").exit == FINISHED
    assert run("import machine\nmachine.reset()\n").exit == "reset"


def test_output_is_streamed_to_the_echo_as_it_is_printed():
    lines = []
    run("import time\nprint('a')\ntime.sleep_ms(5)\nprint('b')\n", echo=lines.append)
    assert "".join(lines) == "a\nb\n"


def test_a_stop_from_outside_ends_the_run():
    from openbricks_sim.run import ProgramRun
    from openbricks_sim.simulation import Simulation

    sim = Simulation()
    try:
        program = ProgramRun(sim)
        program.request_stop()
        result = program.run("import time\ntime.sleep_ms(1000)\n")
    finally:
        sim.close()
    assert result.exit == STOPPED and result.sim_ms == 0


def run_in_own_process(program, *options, cwd):
    """`python -m openbricks_sim.run PROGRAM --json OPTIONS`, importing this process's extension builds."""
    env = dict(os.environ)
    import openbricks_mjcontrol

    import openbricks_native

    paths = {os.path.dirname(openbricks_native.__file__), os.path.dirname(openbricks_mjcontrol.__file__)}
    env["PYTHONPATH"] = os.pathsep.join([*paths, env.get("PYTHONPATH", "")])
    return subprocess.run(
        [sys.executable, "-m", "openbricks_sim.run", str(program), "--json", *options],
        capture_output=True,
        text=True,
        timeout=120,
        env=env,
        cwd=cwd,
    )


@pytest.mark.e2e
def test_the_module_entry_point_runs_a_file_in_its_own_process_and_prints_json(tmp_path):
    program = tmp_path / "mission.py"
    program.write_text(DRIVE_FORWARD)
    out = run_in_own_process(program, "--duration", "5", cwd=tmp_path)
    assert out.returncode == 0, out.stderr
    result = json.loads(out.stdout)
    assert result["exit"] == FINISHED and result["output"].startswith("done at")
    assert result["pose"]["x_mm"] > 500
    assert result["peak_rss_mb"] < 120, "the product's memory bar for a simulator process"


@pytest.mark.e2e
def test_a_run_process_caps_its_memory_and_a_hog_ends_in_its_own_memory_error(tmp_path):
    program = tmp_path / "hog.py"
    program.write_text("blocks = []\nwhile True:\n    blocks.append(bytearray(50 * 1024 * 1024))\n")
    out = run_in_own_process(program, "--memory-mb", "400", cwd=tmp_path)
    result = json.loads(out.stdout)
    assert result["exit"] == MEMORY_LIMIT and out.returncode == 3
    assert "MemoryError" in result["error"]
    assert "memory limit: the program ran out of its 400 MB of memory (--memory-mb)" in result["error"]


def test_a_busy_wait_on_done_finishes_because_python_costs_simulated_time():
    # No sleep in the loop: on a hub the tick runs on while Python spins, and here every call the
    # program makes costs a few simulated microseconds, so the move ends and so does the loop.
    source = (
        "from openbricks.drivers.st3032 import ST3032Motor\n"
        "from openbricks.robotics import DriveBase\n"
        "left = ST3032Motor(servo_id=1, uart_id=1, tx=14, rx=41)\n"
        "right = ST3032Motor(servo_id=2, uart_id=1, tx=14, rx=41, invert=True)\n"
        "db = DriveBase(left, right, wheel_diameter_mm=88, axle_track_mm=138)\n"
        "db.straight(300, wait=False)\n"
        "while not db.done():\n"
        "    pass\n"
        "print('arrived')\n"
    )
    result = run(source, wall_limit_s=120)
    assert result.exit == FINISHED, result.error
    assert result.output == "arrived\n"
    assert abs(result.pose["x_mm"] - 300.0) < 5.0


def test_python_time_is_counted_so_a_run_repeats_exactly():
    source = "n = 0\nwhile n < 20000:\n    n = n + abs(1)\nimport time\nprint(time.ticks_us())\n"
    first, second = run(source), run(source)
    assert first.output == second.output and int(first.output) > 0


def test_a_timer_callback_pays_for_its_python_while_the_program_sleeps():
    # Counting stops while the clock advances (its own code is the hub's), and starts again for each
    # callback that fires on the way: 400 calls in a callback cost 2 ms of simulated time.
    source = (
        "import time\n"
        "from machine import Timer\n"
        "spent = []\n"
        "def busy(_timer):\n"
        "    start = time.ticks_us()\n"
        "    for _ in range(400):\n"
        "        abs(1)\n"
        "    spent.append(time.ticks_diff(time.ticks_us(), start))\n"
        "Timer(0).init(period=100, mode=Timer.PERIODIC, callback=busy)\n"
        "time.sleep_ms(1000)\n"
        "print(len(spent), min(spent))\n"
    )
    result = run(source)
    assert result.exit == FINISHED, result.error
    fired, least_us = map(int, result.output.split())
    assert fired >= 9 and least_us >= 1900
