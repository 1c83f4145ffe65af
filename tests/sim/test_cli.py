"""`openbricks sim run/preview` as a user and a script see them: output, JSON results, clear errors."""

import json
import os
import subprocess
import sys

import pytest

from openbricks_sim import cli

SQUARE_SIDE = """\
from openbricks.drivers.st3032 import ST3032Motor
from openbricks.robotics import DriveBase
left = ST3032Motor(servo_id=1, tx=14, rx=41)
right = ST3032Motor(servo_id=2, tx=14, rx=41, invert=True)
db = DriveBase(left, right, wheel_diameter_mm=56, axle_track_mm=114)
print("driving")
db.straight(100)
print("arrived")
"""


def sim(*args, env=None, timeout=120):
    return subprocess.run(
        [sys.executable, "-m", "openbricks_server.cli", "sim", *args],
        capture_output=True,
        text=True,
        timeout=timeout,
        env=env,
    )


@pytest.fixture
def program(tmp_path):
    path = tmp_path / "side.py"
    path.write_text(SQUARE_SIDE)
    return path


def test_run_streams_the_output_and_ends_with_a_summary(program):
    done = sim("run", str(program))
    assert done.returncode == 0, done.stderr
    assert done.stdout == "driving\narrived\n"
    assert done.stderr.startswith("[finished]") and "robot at x=" in done.stderr


def test_json_result_for_scripts_with_the_start_pose_in_metres_and_ccw_yaw(program):
    done = sim(
        "run",
        str(program),
        "--json",
        "--world",
        "zones",
        "--seed",
        "3",
        "--x",
        "0.3",
        "--y",
        "0.2",
        "--yaw",
        "90",
    )
    assert done.returncode == 0, done.stderr
    result = json.loads(done.stdout)
    assert result["exit"] == "finished" and result["output"] == "driving\narrived\n"
    assert result["job"]["start_mm_deg"] == [300.0, 200.0, -90.0]
    assert result["pose"]["y_mm"] > 250  # yaw 90 (counter-clockwise) drives towards +y
    assert set(result) >= {"pose", "score", "sim_s", "wall_s", "exit"} and "zone" in result["score"]


def test_a_program_error_and_a_time_limit_are_exit_reasons(tmp_path):
    broken = tmp_path / "broken.py"
    broken.write_text("print('before')\nx = 1 / 0\n")
    done = sim("run", str(broken))
    assert done.returncode == 1 and "ZeroDivisionError" in done.stderr and done.stdout == "before\n"
    looping = tmp_path / "loop.py"
    looping.write_text("import time\nwhile True:\n    time.sleep_ms(100)\n")
    done = sim("run", str(looping), "--duration", "0.5", "--json")
    assert json.loads(done.stdout)["exit"] == "time_limit" and json.loads(done.stdout)["sim_s"] == 0.5


def test_no_shim_scripts_drive_the_simulation_themselves(tmp_path):
    script = tmp_path / "direct.py"
    script.write_text("simulation.physics.step(250)\nprint(simulation.physics.now_ms)\n")
    done = sim("run", str(script), "--no-shim", "--json")
    assert done.returncode == 0, done.stderr
    assert done.stdout.splitlines()[0] == "250"
    assert json.loads(done.stdout.splitlines()[1])["sim_s"] == 0.25


def test_user_errors_are_one_line(program):
    done = sim("run", str(program), "--world", "moon")
    assert done.returncode == 1 and "unknown world 'moon': use one of" in done.stderr
    assert "Traceback" not in done.stderr
    done = sim("run", "missing.py")
    assert done.returncode == 1 and "missing.py: no such program file" in done.stderr


def test_a_world_file_is_refused_in_one_line_by_whichever_process_can_tell(program, tmp_path):
    done = sim("run", str(program), "--world", str(tmp_path / "missing.xml"))
    assert done.returncode == 1 and f"world file {tmp_path / 'missing.xml'} does not exist" in done.stderr
    bad = tmp_path / "bad.xml"
    bad.write_text("<mujoco><worldbody><geom type='nonsense'/></worldbody></mujoco>\n")
    # Only MuJoCo can tell the file is no model: the run's process, which loads it, says so.
    done = sim("run", str(program), "--world", str(bad))
    assert done.returncode == 1 and f"world file {bad} is not a model MuJoCo can load: " in done.stderr
    assert "Traceback" not in done.stderr and done.stdout == ""  # the program never started
    done = sim("run", str(program), "--world", str(bad), "--json")
    result = json.loads(done.stdout)
    assert result["exit"] == "error" and "is not a model MuJoCo can load" in result["error"]


# `openbricks sim run` as the console script runs it, telling which of MuJoCo and numpy the CLI's
# own process imported by the time it exits.
PARENT_IMPORTS = """
import atexit, sys
heavy = lambda: sorted({name.split(".")[0] for name in sys.modules} & {"mujoco", "numpy"})
atexit.register(lambda: print("parent imported:", heavy(), file=sys.stderr))
from openbricks_server.cli import main
sys.exit(main(["sim", "run", sys.argv[1]]))
"""


def test_the_cli_process_of_a_run_imports_neither_mujoco_nor_numpy(tmp_path):
    hello = tmp_path / "hello.py"
    hello.write_text("print('hello')\n")
    done = subprocess.run(
        [sys.executable, "-c", PARENT_IMPORTS, str(hello)], capture_output=True, text=True, timeout=120
    )
    assert done.returncode == 0 and done.stdout == "hello\n", done.stderr
    assert done.stderr.splitlines()[-1] == "parent imported: []"  # the child imported them, not us


def test_preview_headless_is_a_smoke_test():
    # Without --headless, preview serves the 3D view: tests/sim/viewer/test_cli_viewer.py.
    done = sim("preview", "--headless", "--world", "line_track", "--duration", "0.5")
    assert done.returncode == 0 and done.stdout.startswith("line_track: 0.5 s of physics")


def test_without_mujoco_every_command_prints_the_install_hint(tmp_path, program):
    broken = tmp_path / "site" / "mujoco"
    broken.mkdir(parents=True)
    (broken / "__init__.py").write_text("raise ImportError('libGL.so.1: cannot open shared object file')\n")
    env = dict(os.environ, PYTHONPATH=os.pathsep.join([str(broken.parent), os.environ.get("PYTHONPATH", "")]))
    done = sim("run", str(program), env=env)
    assert done.returncode == 1 and "pipx install 'openbricks[sim]'" in done.stderr
    assert "Traceback" not in done.stderr
    assert sim("--help", env=env).returncode == 0


def test_the_help_names_every_world():
    from openbricks_sim.worlds import WORLDS

    assert cli.WORLD_NAMES == ", ".join(WORLDS)
