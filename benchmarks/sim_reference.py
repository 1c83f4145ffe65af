"""Our simulator side by side with the reference one (openbricks 4.36.0 from PyPI), whole processes.

Each program is run as a user runs it, `openbricks sim run PROGRAM` on the `empty` world, headless,
by each side's own console script: ours from an installed layout of this checkout
(benchmarks/_installed.py: plain sys.path entries and byte-compiled sources, as a wheel installs
them, rather than the development venv's editable finder), the reference from the benchmarks'
throwaway virtualenv (benchmarks/_reference.py, created once under the user cache dir; only ever run
as a subprocess, nothing of it is imported here). The programs:
- the manual's section 5.1 square with six laps (about 66 s simulated), the mission-length run;
- the same square with one lap (about 11 s simulated), the length of most programs students write;
- a program that only prints: start-up alone.

Ours runs two ways. "ours" is a run as every run after a user's first is: its child forked by the
warm server a first run left behind (sim/shared_server.py; the benchmark starts it with a first run
and stops it at the end, in a runtime folder of its own). "ours, cold" is a user's first run (and
every run with OPENBRICKS_SIM_WARM=0): the CLI forks its own child, which imports MuJoCo itself.

For each, ROUNDS rounds alternating the sides (other processes share the CPU; alternating slows all
alike), best of each side:
- wall time of the whole process, start-up included, and CPU time (user + system of the process
  and the children it waited for, from wait4, plus a warm run's child, reaped by the server: steadier
  than wall time on a busy machine);
- peak resident memory per process (VmHWM of the process and of its run's child, sampled every
  10 ms), and the warm server's own.
The ratios are reference / ours: above 1 means ours is faster or smaller.

Then the stepping figure: the six-lap program's own run (the program phase ours reports, from its
first line to its last, less the physics' build at its first hardware use) against bare `mj_step`
of the same model (the st3032 chassis on `empty`, no control callback) for the same number of
steps, at rest and with the wheels driven, in a process of the installed layout, alternated with
the runs. That ratio is of medians: a shared machine's CPUs run in spells (here mostly at one speed
and now and then, for a fraction of a second, much faster, each CPU on its own), and a best-of
figure favours the shorter run, which fits in a fast spell more often. The best of each is shown
beside it, and every ratio row gives its medians too.

Note: the manual's example wires the left wheel as servo 2 (mirrored) and the right as servo 1; our
simulator mounts the servos where the program's DriveBase says they are, so it drives the same
square, turning right.
"""

from __future__ import annotations

import functools
import json
import os
import signal
import statistics
import subprocess
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path

from benchmarks import Row

REFERENCE_VERSION = "4.36.0"  # what benchmarks._reference installs
ROUNDS = 5
SIM_LIMIT_S = 300
RSS_SAMPLE_S = 0.01
RUN_TIMEOUT_S = 600
TABLE_LAPS = 2  # the reference steps its tables several times slower: keep that run short
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
PRINT_ONLY = 'print("hello")\nprint("mission done")\n'
PROGRAMS = {
    "square x6 laps": MISSION.format(laps=6),
    "square x1 lap": MISSION.format(laps=1),
    "print only": PRINT_ONLY,
}
# How bare MuJoCo steps the same model, in a process of the installed layout: seconds for N steps.
BARE_STEPS = """\
import json, sys, time
import mujoco
from openbricks_sim.physics import Physics
steps, torque = int(sys.argv[1]), float(sys.argv[2])
physics = Physics("empty", "st3032")
physics.data.ctrl[:] = torque
started = time.perf_counter()
mujoco.mj_step(physics.model, physics.data, nstep=steps)
print(json.dumps(time.perf_counter() - started))
"""
DRIVEN_TORQUE_NM = 0.05  # both wheels driven: the robot rolls, as it does for most of the square


@dataclass(frozen=True)
class Measured:
    """One simulator process: what it simulated and what it cost."""

    wall_s: float
    cpu_s: float
    peak_rss_mb: float
    sim_s: float | None = None  # simulated time (None: the program only printed)
    program_s: float | None = None  # the program's own run (ours reports it), without start-up
    build_s: float | None = None  # of program_s, building the physics at its first hardware use


# --- one process, measured --------------------------------------------------------------------------


def _measure(command, cwd, env, servers=()) -> tuple[subprocess.CompletedProcess, float, float, float]:
    """Run command; returns (completed, wall_s, cpu_s, peak_rss_mb) of that process and its run's child:
    the child it forks or, for a warm run, the one its request had a warm server fork (`servers`: their
    pids; the child's CPU time is what the server's reaped children gained meanwhile)."""
    out_path, err_path = Path(cwd) / "stdout.txt", Path(cwd) / "stderr.txt"
    served_cpu_s = sum(_reaped_children_cpu_s(pid) for pid in servers)
    with open(out_path, "wb") as out, open(err_path, "wb") as err:
        start = time.perf_counter()
        process = subprocess.Popen(command, cwd=cwd, env=env, stdout=out, stderr=err)
        peak_kb = 0
        deadline = start + RUN_TIMEOUT_S
        while True:
            family = _family(process.pid) + [pid for server in servers for pid in _family(server)[1:]]
            peak_kb = max(peak_kb, *(_vm_hwm_kb(pid) for pid in family))
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
    served_cpu_s = sum(_reaped_children_cpu_s(pid) for pid in servers) - served_cpu_s
    return completed, wall_s, usage.ru_utime + usage.ru_stime + served_cpu_s, peak_kb / 1024


def _reaped_children_cpu_s(pid: int) -> float:
    """CPU seconds of the children `pid` has waited for (cutime + cstime of /proc/PID/stat)."""
    try:
        with open(f"/proc/{pid}/stat", encoding="ascii") as stat:
            fields = stat.read().rsplit(")", 1)[1].split()
    except OSError:
        return 0.0
    return (int(fields[13]) + int(fields[14])) / os.sysconf("SC_CLK_TCK")


def _family(pid: int) -> list[int]:
    """pid and its descendants now (ours forks the run's child from the CLI)."""
    family, index = [pid], 0
    while index < len(family):
        try:
            for task in os.listdir(f"/proc/{family[index]}/task"):
                with open(f"/proc/{family[index]}/task/{task}/children", encoding="ascii") as children:
                    family += [int(child) for child in children.read().split()]
        except OSError:  # ended meanwhile
            pass
        index += 1
    return family


def _vm_hwm_kb(pid: int) -> int:
    try:
        with open(f"/proc/{pid}/status", encoding="ascii") as status:
            for line in status:
                if line.startswith("VmHWM:"):
                    return int(line.split()[1])
    except OSError:  # already gone
        pass
    return 0


def run_ours(
    program: Path, world: str = "empty", runtime: Path | None = None, warm: bool = False
) -> Measured:
    """One `openbricks sim run`: cold (it forks its own child) or warm (a child of the warm server
    published in `runtime`, as every run after a user's first is)."""
    from benchmarks import _installed

    command = [str(_installed.openbricks()), "sim", "run", str(program), "--world", world]
    command += ["--duration", str(SIM_LIMIT_S), "--json"]
    env = _clean_env()
    if runtime is not None:
        env["OPENBRICKS_RUNTIME_DIR"] = str(runtime)
    env["OPENBRICKS_SIM_WARM"] = "1" if warm else "0"
    servers = _servers(runtime) if warm else ()
    done, wall_s, cpu_s, peak_mb = _measure(command, program.parent, env, servers)
    lines = done.stdout.strip().splitlines()
    if done.returncode != 0 or not lines:
        raise RuntimeError(
            f"our simulator failed (exit {done.returncode}):\n{_tail(done.stdout + done.stderr)}"
        )
    result = json.loads(lines[-1])
    if result["exit"] != "finished" or "mission done" not in result["output"]:
        raise RuntimeError(f"the mission ended with {result['exit']} in our simulator: {result['error']}")
    return Measured(wall_s, cpu_s, peak_mb, result["sim_s"] or None, result["wall_s"], result["build_s"])


def _servers(runtime: Path | None) -> list[int]:
    """Pids of the warm servers published in `runtime` (their lock files name them)."""
    from openbricks_sim.shared_server import server_pid

    if runtime is None:
        return []
    pids = (server_pid(str(socket)) for socket in (runtime / "sim").glob("*.sock"))
    return [pid for pid in pids if pid is not None and os.path.exists(f"/proc/{pid}")]


def start_warm_server(runtime: Path, folder: Path) -> int:
    """A first run, which leaves the warm server behind; its pid once it is published."""
    (folder / "first.py").write_text(PRINT_ONLY, encoding="utf-8")
    run_ours(folder / "first.py", runtime=runtime, warm=True)
    deadline = time.monotonic() + RUN_TIMEOUT_S
    while not list((runtime / "sim").glob("*.sock")):
        if time.monotonic() > deadline:
            raise RuntimeError(f"no warm server was published in {runtime / 'sim'}")
        time.sleep(0.05)
    return _servers(runtime)[0]


def stop_warm_servers(runtime: Path) -> None:
    for pid in _servers(runtime):
        os.kill(pid, signal.SIGTERM)


def run_reference(program: Path, world: str = "empty") -> Measured:
    from benchmarks import _reference as reference

    trace = program.parent / "trace.csv"
    trace.unlink(missing_ok=True)
    command = [str(reference.script("openbricks")), "sim", "run", str(program), "--world", world]
    command += ["--trace", str(trace), "--max-sim-s", str(SIM_LIMIT_S)]
    done, wall_s, cpu_s, peak_mb = _measure(command, program.parent, _clean_env())
    if done.returncode != 0 or "mission done" not in done.stdout:
        raise RuntimeError(
            f"the reference simulator failed on {world} (exit {done.returncode}):\n"
            f"{_tail(done.stdout + done.stderr)}"
        )
    # The trace has a row every 50 ms of simulated time: its last row is the run's length to 0.05 s.
    rows = trace.read_text(encoding="ascii").strip().splitlines() if trace.exists() else []
    sim_s = int(rows[-1].split(",")[0]) / 1000 if len(rows) > 1 else None
    return Measured(wall_s, cpu_s, peak_mb, sim_s)


def bare_steps_s(steps: int, torque_nm: float) -> float:
    """Seconds bare mj_step takes for `steps` steps of the st3032 chassis on `empty` (installed layout)."""
    from benchmarks import _installed

    python = _installed.openbricks().with_name("python")
    done = subprocess.run(
        [str(python), "-c", BARE_STEPS, str(steps), str(torque_nm)],
        capture_output=True,
        text=True,
        check=True,
        timeout=RUN_TIMEOUT_S,
        env=_clean_env(),
    )
    return json.loads(done.stdout)


def _clean_env() -> dict:
    """This environment without what would let one simulator's packages shadow the other's."""
    env = {k: v for k, v in os.environ.items() if k not in ("PYTHONPATH", "PYTHONHOME", "VIRTUAL_ENV")}
    env["PYTHONDONTWRITEBYTECODE"] = "1"
    return env


def _tail(text: str, lines: int = 20) -> str:
    return "\n".join(text.strip().splitlines()[-lines:])


# --- the figures --------------------------------------------------------------------------------------


def side_by_side() -> list[Row]:
    ours = {name: [] for name in PROGRAMS}
    cold = {name: [] for name in PROGRAMS}
    reference = {name: [] for name in PROGRAMS}
    bare = {"at rest": [], "driven": []}
    with tempfile.TemporaryDirectory(prefix="ob-bench-ref-") as tmp:
        runtime = Path(tmp) / "runtime"
        server = start_warm_server(runtime, Path(tmp))
        try:
            for round_ in range(ROUNDS):
                for index, (name, source) in enumerate(PROGRAMS.items()):
                    folders = {side: Path(tmp) / f"{side}-{index}" for side in ("ours", "cold", "reference")}
                    for folder in folders.values():
                        folder.mkdir(exist_ok=True)
                        (folder / "program.py").write_text(source, encoding="utf-8")
                    # Alternate the order, so no side always runs on a warmer cache.
                    order = [
                        ("reference", run_reference, reference),
                        ("ours", functools.partial(run_ours, runtime=runtime, warm=True), ours),
                        ("cold", functools.partial(run_ours, runtime=runtime), cold),
                    ]
                    for side, run, into in order if round_ % 2 == 0 else reversed(order):
                        into[name].append(run(folders[side] / "program.py"))
                steps = round(ours["square x6 laps"][-1].sim_s * 1000)
                bare["at rest"].append(bare_steps_s(steps, 0.0))
                bare["driven"].append(bare_steps_s(steps, DRIVEN_TORQUE_NM))
            server_mb = _vm_hwm_kb(server) / 1024
        finally:
            stop_warm_servers(runtime)
    rows = []
    for name in PROGRAMS:
        rows += _program_rows(name, ours[name], reference[name])
        rows += _program_rows(name, cold[name], reference[name], "ours, cold (a user's first run)")[1:]
    rows += _stepping_rows(ours["square x6 laps"], bare)
    peak_ours = max(m.peak_rss_mb for runs in (*ours.values(), *cold.values()) for m in runs)
    peak_ref = max(m.peak_rss_mb for runs in reference.values() for m in runs)
    rows += [
        Row(f"reference {REFERENCE_VERSION} peak memory per process", peak_ref, "MB", "VmHWM, any program"),
        Row("ours peak memory per process", peak_ours, "MB", "VmHWM, CLI and child; bar: <= 120 MB"),
        Row(
            "ours: the warm server's own memory", server_mb, "MB", "VmHWM; one per user, shared by every run"
        ),
    ]
    return rows


def _program_rows(
    name: str, ours: list[Measured], reference: list[Measured], label: str = "ours"
) -> list[Row]:
    best_ours = min(ours, key=lambda m: m.wall_s)
    best_ref = min(reference, key=lambda m: m.wall_s)
    cpu_ours = min(m.cpu_s for m in ours)
    cpu_ref = min(m.cpu_s for m in reference)
    median_ratio = statistics.median(m.wall_s for m in reference) / statistics.median(m.wall_s for m in ours)
    simulated = f"{best_ours.sim_s:.1f} s simulated, " if best_ours.sim_s else ""
    return [
        Row(f"{name}: reference {REFERENCE_VERSION}", best_ref.wall_s, "s wall", f"cpu {cpu_ref:.2f} s"),
        Row(
            f"{name}: {label}",
            best_ours.wall_s,
            "s wall",
            f"cpu {cpu_ours:.2f} s; {simulated}program {best_ours.program_s:.2f} s",
        ),
        Row(
            f"{name}: speed ratio (reference / {label})",
            best_ref.wall_s / best_ours.wall_s,
            "x",
            f"whole process, wall, best of {len(ours)}; medians {median_ratio:.2f}x; "
            f"cpu {cpu_ref / cpu_ours:.2f}x",
        ),
    ]


def _stepping_rows(runs: list[Measured], bare: dict[str, list[float]]) -> list[Row]:
    # The program's own stepping: its run less the physics' build, which is start-up (counted in the
    # whole-process figures above) that happens to fall at the program's first hardware use.
    stepping = [m.program_s - (m.build_s or 0.0) for m in runs]
    program_s = statistics.median(stepping)
    sim_s = runs[0].sim_s
    rows = [
        Row(
            "six laps: program phase",
            sim_s / program_s,
            "x real time",
            f"median {program_s:.3f} s for {sim_s:.1f} s (best {min(stepping):.3f} s), the build apart",
        )
    ]
    for how, seconds in bare.items():
        median = statistics.median(seconds)
        rows.append(
            Row(
                f"bare mj_step, same model, {how}",
                sim_s / median,
                "x real time",
                f"median {median:.3f} s (best {min(seconds):.3f} s)",
            )
        )
        rows.append(
            Row(
                f"stepping / bare mj_step {how}",
                median / program_s * 100,
                "%",
                f"medians; best of each {min(seconds) / min(stepping) * 100:.0f} %; bar: >= 80 %",
            )
        )
    return rows


def on_tables() -> list[Row]:
    with tempfile.TemporaryDirectory(prefix="ob-bench-ref-table-") as tmp:
        folders = {name: Path(tmp) / name for name in ("ours", "reference")}
        for folder in folders.values():
            folder.mkdir()
            (folder / "program.py").write_text(MISSION.format(laps=TABLE_LAPS), encoding="utf-8")
        reference = run_reference(folders["reference"] / "program.py", REFERENCE_TABLE)
        ours = run_ours(folders["ours"] / "program.py", OUR_TABLE)
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
    ]


def run() -> list[Row]:
    return side_by_side() + on_tables()
