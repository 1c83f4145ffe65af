"""The physics is built when the program first touches the hardware, and not before."""

import subprocess
import sys

from openbricks_sim.job import FINISHED
from openbricks_sim.run import run_program
from openbricks_sim.simulation import Simulation

ONLY_COMPUTES = "import time\nn = sum(range(1000))\ntime.sleep_ms(250)\nprint(n, time.ticks_ms())\n"


def test_a_program_that_only_computes_never_loads_mujoco():
    check = (
        "import sys\n"
        "from openbricks_sim.run import run_program\n"
        f"result = run_program('compute.py', source={ONLY_COMPUTES!r})\n"
        "print(result.exit, result.output.strip(), result.pose, 'mujoco' in sys.modules)\n"
    )
    done = subprocess.run([sys.executable, "-c", check], capture_output=True, text=True, timeout=120)
    assert done.returncode == 0, done.stderr
    assert done.stdout.strip().endswith("False"), done.stdout
    assert done.stdout.startswith("finished 499500 25")
    assert "'x_mm': 0.0, 'y_mm': 0.0, 'heading_deg': 0.0" in done.stdout
    assert run_program("compute.py", source=ONLY_COMPUTES).build_s is None


def test_hardware_first_touched_late_runs_on_the_programs_time():
    source = (
        "import time\n"
        "time.sleep_ms(1500)\n"
        "from openbricks.drivers.st3032 import ST3032Motor\n"
        "left = ST3032Motor(1)\n"
        "right = ST3032Motor(2, invert=True)\n"
        "left.run_speed(360)\n"
        "right.run_speed(360)\n"
        "time.sleep_ms(2000)\n"
        "left.brake()\n"
        "right.brake()\n"
        "time.sleep_ms(300)\n"
        "print(time.ticks_ms())\n"
    )
    late = run_program("late.py", source=source)
    on_time = run_program("now.py", source=source.replace("time.sleep_ms(1500)\n", ""))
    assert late.exit == on_time.exit == FINISHED, late.error
    assert int(late.output) - int(on_time.output) in range(1495, 1506)
    assert abs(late.pose["x_mm"] - on_time.pose["x_mm"]) < 1.0, "the same drive, 1.5 s later"
    assert 0 < late.build_s < late.wall_s, "the build is part of the run's wall time, and said so"


def test_the_start_pose_is_where_an_untouched_robot_rests():
    sim = Simulation("empty", "st3032", start_mm_deg=(100.0, -50.0, 30.0))
    try:
        assert sim.resting_pose_mm_deg() == (100.0, -50.0, 30.0) and not sim.built
        pose = sim.physics.pose()
        assert (round(pose.x_mm), round(pose.y_mm), round(pose.heading_deg)) == (100, -50, 30)
        assert sim.resting_pose_mm_deg() is None, "built: the physics says where it is"
    finally:
        sim.close()


def test_the_empty_worlds_start_is_the_origin_as_the_world_says():
    from openbricks_sim.worlds import WORLDS

    sim = Simulation("empty")
    try:
        assert sim.resting_pose_mm_deg() == WORLDS["empty"].start_mm_deg
    finally:
        sim.close()
