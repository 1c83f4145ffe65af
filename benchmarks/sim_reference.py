"""Our simulator side by side with the reference one (openbricks 4.36.0 from PyPI) on the same program.

The program is the manual's square example (section 5.1) with more laps, a 60 s-class mission,
run unchanged by both simulators on their `empty` worlds, headless, each in a process of its own
started the way a user would start it (`python -m <their sim module> run ...`). The reference lives
in the benchmarks' throwaway virtualenv (benchmarks._reference: `openbricks[sim]==4.36.0`, created once
under the user cache dir) and is only ever run as a subprocess: nothing of it is imported here.

For each side, best of ROUNDS alternating runs (other processes share the CPU; alternating slows
both alike):
- wall time per simulated second of the whole process (start-up, world build, the mission);
- CPU time per simulated second (user + system, from wait4: steadier than wall time on a busy
  machine);
- peak resident memory (VmHWM, sampled every 10 ms while the process runs: the parent's pages, which
  getrusage would charge to a spawned child, are not counted).
The ratios are reference / ours: above 1 means ours is faster or smaller. Product bars: >= 1.5x the
reference's speed, <= 120 MB per simulator process.

Then one run each on the simulators' own competition tables (ours `wro`, theirs `wro-2026-senior`):
different tables, so only an indication of how each copes with walls and props.

Note: the manual's example wires the left wheel as servo 2 (mirrored) and the right as servo 1; our
simulator mounts the servos where the program's DriveBase says they are, so it drives the same
square, turning right.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path

from benchmarks import Row

REFERENCE_VERSION = "4.36.0"  # what benchmarks._reference installs
LAPS = 6  # about 66 s of simulated time
TABLE_LAPS = 2  # the reference steps its tables several times slower: keep that run short
ROUNDS = 5
SIM_LIMIT_S = 300
RSS_SAMPLE_S = 0.01
RUN_TIMEOUT_S = 600

OUR_TABLE = "wro"
REFERENCE_TABLE = "wro-2026-senior"

# The workload of the manual's section 5.1 square (same wiring, geometry, speeds and 200 mm sides),
# with the lap count raised to make a mission; written here for the benchmark.
MISSION = """\
from openbricks.drivers.st3032 import ST3032Motor
from openbricks.robotics import DriveBase

left = ST3032Motor(servo_id=2, uart_id=1, tx=14, rx=41, invert=True)
right = ST3032Motor(servo_id=1, uart_id=1, tx=14, rx=41)
base = DriveBase(left, right, wheel_diameter_mm=88, axle_track_mm=136)
base.settings(straight_speed=150, turn_rate=200)
for lap in range({laps}):
    for side in range(4):
        base.straight(200)
        base.turn(90)
    print("lap", lap + 1, "done")
print("mission done")
"""


@dataclass(frozen=True)
class Measured:
    """One simulator process: what it simulated and what it cost."""

    sim_s: float
    wall_s: float
    cpu_s: float
    peak_rss_mb: float
    program_s: float | None = None  # the program run alone (ours reports it), without start-up

    @property
    def wall_ms_per_sim_s(self) -> float:
        return self.wall_s / self.sim_s * 1000

    @property
    def cpu_ms_per_sim_s(self) -> float:
        return self.cpu_s / self.sim_s * 1000

    def summary(self) -> str:
        return (
            f"{self.sim_s:.1f} s simulated in {self.wall_s:.2f} s ({self.sim_s / self.wall_s:.0f}x real time)"
        )


# --- one process, measured --------------------------------------------------------------------------


def _measure(command, cwd, env) -> tuple[subprocess.CompletedProcess, float, float, float]:
    """Run command; returns (completed, wall_s, cpu_s, peak_rss_mb) of that process alone."""
    out_path, err_path = Path(cwd) / "stdout.txt", Path(cwd) / "stderr.txt"
    with open(out_path, "wb") as out, open(err_path, "wb") as err:
        start = time.perf_counter()
        process = subprocess.Popen(command, cwd=cwd, env=env, stdout=out, stderr=err)
        peak_kb = 0
        deadline = start + RUN_TIMEOUT_S
        while True:
            peak_kb = max(peak_kb, _vm_hwm_kb(process.pid))
            pid, status, usage = os.wait4(process.pid, os.WNOHANG)
            if pid == process.pid:
                break
            if time.perf_counter() > deadline:
                process.kill()
                os.wait4(process.pid, 0)
                raise RuntimeError(f"`{' '.join(map(str, command))}` ran over {RUN_TIMEOUT_S} s")
            time.sleep(RSS_SAMPLE_S)
        wall_s = time.perf_counter() - start
    process.returncode = os.waitstatus_to_exitcode(status)
    completed = subprocess.CompletedProcess(
        command,
        process.returncode,
        out_path.read_text(encoding="utf-8", errors="replace"),
        err_path.read_text(encoding="utf-8", errors="replace"),
    )
    return completed, wall_s, usage.ru_utime + usage.ru_stime, peak_kb / 1024


def _vm_hwm_kb(pid: int) -> int:
    try:
        with open(f"/proc/{pid}/status", encoding="ascii") as status:
            for line in status:
                if line.startswith("VmHWM:"):
                    return int(line.split()[1])
    except OSError:  # already gone
        pass
    return 0


def run_ours(program: Path, world: str) -> Measured:
    import openbricks_mjcontrol

    import openbricks_native

    env = _clean_env()
    # The child imports the same builds of the extensions as this process (a private build included).
    paths = {os.path.dirname(openbricks_native.__file__), os.path.dirname(openbricks_mjcontrol.__file__)}
    env["PYTHONPATH"] = os.pathsep.join([*paths, os.environ.get("PYTHONPATH", "")])
    command = [
        sys.executable,
        "-m",
        "openbricks_sim.run",
        str(program),
        "--world",
        world,
        "--duration",
        str(SIM_LIMIT_S),
        "--json",
    ]
    done, wall_s, cpu_s, peak_mb = _measure(command, program.parent, env)
    lines = done.stdout.strip().splitlines()
    if done.returncode != 0 or not lines:
        raise RuntimeError(
            f"our simulator failed (exit {done.returncode}):\n{_tail(done.stdout + done.stderr)}"
        )
    result = json.loads(lines[-1])
    if result["exit"] != "finished":
        raise RuntimeError(f"the mission ended with {result['exit']} in our simulator: {result['error']}")
    return Measured(result["sim_ms"] / 1000, wall_s, cpu_s, peak_mb, program_s=result["wall_s"])


def run_reference(program: Path, world: str) -> Measured:
    from benchmarks import _reference as reference

    trace = program.parent / "trace.csv"
    command = [
        str(reference.python()),
        "-m",
        "openbricks_sim",
        "run",
        str(program),
        "--world",
        world,
        "--trace",
        str(trace),
        "--max-sim-s",
        str(SIM_LIMIT_S),
    ]
    done, wall_s, cpu_s, peak_mb = _measure(command, program.parent, _clean_env())
    if done.returncode != 0 or "mission done" not in done.stdout:
        raise RuntimeError(
            f"the reference simulator failed on {world} (exit {done.returncode}):\n"
            f"{_tail(done.stdout + done.stderr)}"
        )
    # The trace has a row every 50 ms of simulated time: its last row is the run's length to 0.05 s.
    last = trace.read_text(encoding="ascii").strip().splitlines()[-1]
    return Measured(int(last.split(",")[0]) / 1000, wall_s, cpu_s, peak_mb)


def _clean_env() -> dict:
    """This environment without what would let one simulator's packages shadow the other's."""
    env = {k: v for k, v in os.environ.items() if k not in ("PYTHONPATH", "PYTHONHOME", "VIRTUAL_ENV")}
    env["PYTHONDONTWRITEBYTECODE"] = "1"
    return env


def _tail(text: str, lines: int = 20) -> str:
    return "\n".join(text.strip().splitlines()[-lines:])


# --- the figures --------------------------------------------------------------------------------------


def _program(folder: Path, laps: int) -> Path:
    path = folder / "square.py"
    path.write_text(MISSION.format(laps=laps), encoding="utf-8")
    return path


def _precompile_ours() -> None:
    """Byte-compile our packages, as pip does for the reference when it installs it: the processes run
    with PYTHONDONTWRITEBYTECODE, and a source checkout would otherwise recompile every module."""
    root = Path(__file__).resolve().parent.parent
    folders = [str(root / name) for name in ("openbricks", "sim", "server")]
    subprocess.run([sys.executable, "-m", "compileall", "-q", *folders], check=True, timeout=300)


def side_by_side() -> list[Row]:
    _precompile_ours()
    ours, reference = [], []
    with tempfile.TemporaryDirectory(prefix="ob-bench-ref-") as tmp:
        folders = {name: Path(tmp) / name for name in ("ours", "reference")}
        for folder in folders.values():
            folder.mkdir()
        for _ in range(ROUNDS):
            reference.append(run_reference(_program(folders["reference"], LAPS), "empty"))
            ours.append(run_ours(_program(folders["ours"], LAPS), "empty"))
    best_ours = min(ours, key=lambda m: m.wall_s)
    best_ref = min(reference, key=lambda m: m.wall_s)
    cpu_ours = min(m.cpu_ms_per_sim_s for m in ours)
    cpu_ref = min(m.cpu_ms_per_sim_s for m in reference)
    peak_ours = max(m.peak_rss_mb for m in ours)
    peak_ref = max(m.peak_rss_mb for m in reference)
    mission = f"manual 5.1 square x{LAPS} laps, empty world"
    return [
        Row(
            f"reference {REFERENCE_VERSION}: {mission}",
            best_ref.wall_ms_per_sim_s,
            "ms wall / sim s",
            best_ref.summary(),
        ),
        Row(
            f"ours: {mission}",
            best_ours.wall_ms_per_sim_s,
            "ms wall / sim s",
            best_ours.summary(),
        ),
        Row(
            "speed ratio, whole process wall time (reference / ours)",
            best_ref.wall_ms_per_sim_s / best_ours.wall_ms_per_sim_s,
            "x",
            "product bar: >= 1.5x",
        ),
        Row(
            "ours: start-up outside the program run",
            (best_ours.wall_s - best_ours.program_s) * 1000,
            "ms",
            f"interpreter, imports, world build; the run itself {best_ours.sim_s / best_ours.program_s:.0f}x",
        ),
        Row("reference CPU time per simulated second", cpu_ref, "ms cpu / sim s", "user + system"),
        Row("ours CPU time per simulated second", cpu_ours, "ms cpu / sim s", "user + system"),
        Row(
            "speed ratio, CPU time (reference / ours)", cpu_ref / cpu_ours, "x", "steadier on a busy machine"
        ),
        Row(f"reference {REFERENCE_VERSION} peak memory per process", peak_ref, "MB", "VmHWM"),
        Row("ours peak memory per process", peak_ours, "MB", "VmHWM; product bar: <= 120 MB"),
        Row("memory ratio (reference / ours)", peak_ref / peak_ours, "x"),
    ]


def on_tables() -> list[Row]:
    with tempfile.TemporaryDirectory(prefix="ob-bench-ref-table-") as tmp:
        folders = {name: Path(tmp) / name for name in ("ours", "reference")}
        for folder in folders.values():
            folder.mkdir()
        reference = run_reference(_program(folders["reference"], TABLE_LAPS), REFERENCE_TABLE)
        ours = run_ours(_program(folders["ours"], TABLE_LAPS), OUR_TABLE)
    return [
        Row(
            f"reference on its {REFERENCE_TABLE} table: real-time factor",
            reference.sim_s / reference.wall_s,
            "x",
            f"{reference.sim_s:.1f} s simulated, whole process; peak {reference.peak_rss_mb:.0f} MB",
        ),
        Row(
            f"ours on the {OUR_TABLE} table: real-time factor",
            ours.sim_s / ours.wall_s,
            "x",
            f"{ours.sim_s:.1f} s simulated, whole process; peak {ours.peak_rss_mb:.0f} MB; bar >= 30x",
        ),
        Row(
            "table speed ratio (reference / ours, different tables)",
            reference.wall_ms_per_sim_s / ours.wall_ms_per_sim_s,
            "x",
            "indicative only",
        ),
    ]


def run() -> list[Row]:
    return side_by_side() + on_tables()
