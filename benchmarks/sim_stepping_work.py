"""The six-lap square's stepping as work rather than time: instructions per simulated millisecond, ours
against bare `mj_step` of the same model, counted by valgrind's callgrind.

sim_reference gives the same comparison in wall-clock time, and that is what a user waits for; but on
a shared machine whose CPUs run in spells (mostly at one speed, now and then much faster, each CPU on
its own) that ratio moves by 15 % or more from one run to the next. An instruction count does not
move, so this says how much work the simulator adds to the physics, run after run.

Each side runs twice under callgrind: the square of sim_reference with six laps and with one lap.
Ours is the program run as `openbricks sim run`'s child runs it (openbricks_sim.run.run_program: the
hub runtime, its Python-time charge, the clock, the native control path and MuJoCo), bare is
`mj_step` of the st3032 chassis on `empty` with both wheels driven, for the same numbers of steps.
The difference of a side's two counts is five laps of stepping, with start-up, imports and the
physics' build cancelled out. Instructions are not time (MuJoCo's dense loops retire more of them per
cycle than the interpreter does), so read this beside the wall-clock ratio, not instead of it.
"""

from __future__ import annotations

import json
import re
import shutil
import subprocess
import tempfile
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

from benchmarks import Row
from benchmarks.sim_reference import BARE_STEPS, DRIVEN_TORQUE_NM, MISSION, SIM_LIMIT_S

LAPS = (6, 1)
RUN_TIMEOUT_S = 1800  # a six-lap run takes a few minutes under callgrind
OURS = """\
import json, sys
from openbricks_sim.run import run_program
result = run_program(sys.argv[1], limit_ms=int(sys.argv[2]))
assert result.exit == "finished", result.error
print(json.dumps(result.sim_ms))
"""
_COLLECTED = re.compile(r"Collected\s*:\s*(\d+)")


def _instructions(python: Path, args: list[str]) -> tuple[int, str]:
    """Instructions the process executed (callgrind's count) and its stdout."""
    done = subprocess.run(
        ["valgrind", "--tool=callgrind", "--callgrind-out-file=/dev/null", str(python), *args],
        capture_output=True,
        text=True,
        timeout=RUN_TIMEOUT_S,
    )
    found = _COLLECTED.search(done.stderr)
    if done.returncode != 0 or found is None:
        raise RuntimeError(f"callgrind run failed (exit {done.returncode}):\n{done.stderr[-2000:]}")
    return int(found.group(1)), done.stdout


def run() -> list[Row]:
    if shutil.which("valgrind") is None:
        raise RuntimeError("this benchmark counts instructions with valgrind: apt install valgrind")
    from benchmarks import _installed

    python = _installed.openbricks().with_name("python")
    with tempfile.TemporaryDirectory(prefix="ob-bench-work-") as tmp:
        programs = {}
        for laps in LAPS:
            programs[laps] = Path(tmp) / f"square_{laps}.py"
            programs[laps].write_text(MISSION.format(laps=laps), encoding="utf-8")
        limit_ms = str(SIM_LIMIT_S * 1000)
        with ThreadPoolExecutor(max_workers=2) as pool:  # one process per core
            ours = {
                laps: pool.submit(_instructions, python, ["-c", OURS, str(path), limit_ms])
                for laps, path in programs.items()
            }
            counted = {laps: future.result() for laps, future in ours.items()}
            steps = {laps: json.loads(out) for laps, (_count, out) in counted.items()}
            bare = {
                laps: pool.submit(_instructions, python, ["-c", BARE_STEPS, str(n), str(DRIVEN_TORQUE_NM)])
                for laps, n in steps.items()
            }
            bare_counts = {laps: future.result()[0] for laps, future in bare.items()}
    long, short = LAPS
    lap_steps = steps[long] - steps[short]
    ours_per_ms = (counted[long][0] - counted[short][0]) / lap_steps
    bare_per_ms = (bare_counts[long] - bare_counts[short]) / lap_steps
    return [
        Row("ours: five laps of the square", ours_per_ms, "instr/ms", f"{lap_steps} simulated ms of program"),
        Row("bare mj_step, same model, driven", bare_per_ms, "instr/ms", "the same steps"),
        Row(
            "stepping / bare mj_step, as work",
            bare_per_ms / ours_per_ms * 100,
            "%",
            "callgrind instruction counts; the wall-clock figure is sim_reference's",
        ),
    ]
