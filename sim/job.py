"""One simulator run as data: `SimJob` in, `SimResult` out.

    job = SimJob("square.py", world="wro", seed=7, limit_ms=30_000)
    child_argv = ["--job", job.to_json()]          # what a child process or a daemon stores
    SimJob.from_dict(json.loads(...)) == job

A run is a pure function of its job: the same job gives the same result (simulated Python time
is charged per call, so a run repeats exactly), which is what lets a sweep farm seeds out to other
processes or machines and compare them. Every front end builds a SimJob and nothing else:
`openbricks sim run` and `sim sweep` (through add_*_arguments/job_from_args, the one definition
of the job's options), the child process that runs it (`python -m openbricks_sim.run --job`),
the 3D viewer's session, and the console's daemon (to_dict/from_dict, stored with the run).

This module imports neither MuJoCo nor the runtime, so the CLI's `--help`, the daemon and the
parent of a contained run stay light: `world_file` checks a --world as far as it can without
MuJoCo (worlds.resolve builds on it), and the world is resolved only by job_from_args, when a
start option needs its start pose.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import sys
from dataclasses import asdict, dataclass, field, fields, replace

from .limits import DEFAULT_MEMORY_MB, default_cpu_s, default_wall_s

CHASSIS_NAMES = ("st3032", "jgb37")
RANGE_FINDERS = ("vl53l0x", "vl53l1x")  # kept in step with sensors.rig by a test
BARE_0X29_PARTS = ("tcs34725", "vl53l0x", "vl53l1x")
WORLD_ALIASES = ("empty", "line_track", "zones", "arena", "wro")  # kept in step with worlds.WORLDS by a test
WORLD_NAMES = ", ".join(WORLD_ALIASES)
DEFAULT_LIMIT_MS = 60_000

# How a run ends (SimResult.exit).
FINISHED = "finished"  # the program returned (or called sys.exit())
ERROR = "error"  # it raised
TIME_LIMIT = "time_limit"  # simulated time ran out
WALL_LIMIT = "wall_limit"  # it ran too long on the wall clock (a loop that never lets time pass)
CPU_LIMIT = "cpu_limit"  # it used up the processor time of its process
MEMORY_LIMIT = "memory_limit"  # it ran out of the memory of its process
STOPPED = "stopped"  # stopped from outside (Ctrl-C, a stopped job)
RESET = "reset"  # machine.reset()

# The exit status of a run, by its exit reason: 0 it finished or used its simulated time, 1 it
# raised (or reset the hub), 3 a limit of its process stopped it, 130 it was interrupted.
EXIT_LIMIT = 3
EXIT_STOPPED = 130
EXIT_STATUS = {
    FINISHED: 0,
    TIME_LIMIT: 0,
    ERROR: 1,
    RESET: 1,
    WALL_LIMIT: EXIT_LIMIT,
    CPU_LIMIT: EXIT_LIMIT,
    MEMORY_LIMIT: EXIT_LIMIT,
    STOPPED: EXIT_STOPPED,
}


class JobError(ValueError):
    """A job that cannot run as given; the message names the field and what it accepts."""


INSTALL_HINT = (
    "the simulator needs MuJoCo, which comes with the [sim] extra: pipx install 'openbricks[sim]' "
    "(or pip install 'openbricks[sim]')"
)


class SimulatorUnavailable(BaseException):
    """MuJoCo would not load when the program first touched the hardware: the run ends with the install
    hint. A BaseException, so a program's `except Exception` cannot carry on without a robot."""


class UnknownWorldError(ValueError):
    """A --world that names no world: the message says what it accepts."""


def world_file(name_or_path: str):
    """None for a world alias; else the MJCF file it names, as a Path that exists and ends in .xml.

    Whether MuJoCo can load the file is worlds.resolve's to find out: this stays MuJoCo-free."""
    if name_or_path in WORLD_ALIASES:
        return None
    from pathlib import Path

    from .world_file import open_world

    spec = open_world(name_or_path)  # a world file or IMAGE@WxH: checked whole, every problem told
    if spec is not None:
        return spec.path
    path = Path(name_or_path)
    if path.suffix.lower() == ".xml" or path.exists():
        if not path.is_file():
            raise UnknownWorldError(f"world file {path} does not exist")
        if path.suffix.lower() != ".xml":
            raise UnknownWorldError(
                f"world file {path} is not an MJCF model: give an .xml file, or a world name"
            )
        return path
    known = ", ".join(sorted(WORLD_ALIASES))
    raise UnknownWorldError(
        f"unknown world {name_or_path!r}: use one of {known}, a world file (.toml) or an MJCF file (.xml)"
    )


@dataclass(frozen=True)
class SimJob:
    """What one run computes from. Units are the simulator's: mm, Pybricks' clockwise heading, ms.

    chassis None: the build whose motors the program constructs. speed None: as fast as the CPU
    allows. wall_limit_s / cpu_limit_s None: derived from limit_ms and speed (limits.py); 0: none.
    memory_mb 0: none. hub_dir None: a fresh temporary hub flash for the run.
    """

    program: str
    world: str = "empty"
    chassis: str | None = None
    seed: int = 0
    start_mm_deg: tuple[float, float, float] | None = None
    speed: float | None = None
    limit_ms: int = DEFAULT_LIMIT_MS
    wall_limit_s: float | None = None
    cpu_limit_s: float | None = None
    memory_mb: int = DEFAULT_MEMORY_MB
    hub_dir: str | None = None
    range_finder: str = "vl53l0x"
    bare_0x29: str | None = None

    def __post_init__(self):
        for name in ("program", "hub_dir"):  # a pathlib.Path is as good as its text
            if isinstance(getattr(self, name), os.PathLike):
                object.__setattr__(self, name, os.fspath(getattr(self, name)))
        _check(isinstance(self.program, str) and self.program, "program", "a program file name")
        _check(isinstance(self.world, str) and self.world, "world", f"a world ({WORLD_NAMES}) or MJCF file")
        _check(self.chassis in (None, *CHASSIS_NAMES), "chassis", f"one of {', '.join(CHASSIS_NAMES)}")
        _check(_whole(self.seed) and self.seed >= 0, "seed", "a whole number from 0 up")
        if self.start_mm_deg is not None:
            start = tuple(self.start_mm_deg)
            ok = len(start) == 3 and all(_number(v) and math.isfinite(v) for v in start)
            _check(ok, "start_mm_deg", "three finite numbers: x_mm, y_mm, heading_deg")
            object.__setattr__(self, "start_mm_deg", tuple(float(v) for v in start))
        _check(
            self.speed is None or (_number(self.speed) and 0 < self.speed < math.inf),
            "speed",
            "a positive real-time factor, or none for as fast as possible",
        )
        _check(_whole(self.limit_ms) and self.limit_ms > 0, "limit_ms", "a positive whole number of ms")
        for name in ("wall_limit_s", "cpu_limit_s"):
            value = getattr(self, name)
            _check(
                value is None or (_number(value) and 0 <= value < math.inf),
                name,
                "seconds from 0 up (0: no limit)",
            )
        _check(_whole(self.memory_mb) and self.memory_mb >= 0, "memory_mb", "MB from 0 up (0: no limit)")
        _check(self.hub_dir is None or isinstance(self.hub_dir, str), "hub_dir", "a directory path")
        _check(self.range_finder in RANGE_FINDERS, "range_finder", f"one of {', '.join(RANGE_FINDERS)}")
        _check(
            self.bare_0x29 in (None, *BARE_0X29_PARTS), "bare_0x29", f"one of {', '.join(BARE_0X29_PARTS)}"
        )

    # --- limits -------------------------------------------------------------------------------

    def wall_limit(self, watched: bool = False) -> float | None:
        """Wall-clock seconds the run may take (None: no limit). A watched run (the 3D viewer) may
        be paused or slowed at will, so it has none unless the job sets one."""
        if self.wall_limit_s is None:
            return None if watched else default_wall_s(self.limit_ms, self.speed)
        return self.wall_limit_s or None

    def cpu_limit(self, watched: bool = False) -> float | None:
        """Processor seconds of the run's process (None: no limit)."""
        if self.cpu_limit_s is None:
            return default_cpu_s(self.wall_limit(watched))
        return self.cpu_limit_s or None

    # --- as data --------------------------------------------------------------------------------

    def to_dict(self) -> dict:
        data = asdict(self)
        if self.start_mm_deg is not None:
            data["start_mm_deg"] = list(self.start_mm_deg)
        return data

    def to_json(self) -> str:
        return json.dumps(self.to_dict())

    @classmethod
    def from_dict(cls, data: dict) -> SimJob:
        """The job a to_dict() made (JobError for unknown or bad fields: data from outside)."""
        if not isinstance(data, dict):
            raise JobError(f"a sim job is a JSON object of its fields, not {type(data).__name__}")
        known = {f.name for f in fields(cls)}
        unknown = sorted(set(data) - known)
        if unknown:
            raise JobError(
                f"unknown sim job field(s) {', '.join(unknown)}: the fields are {', '.join(sorted(known))}"
            )
        if "program" not in data:
            raise JobError("a sim job needs its program")
        return cls(**data)

    def with_seed(self, seed: int) -> SimJob:
        return replace(self, seed=seed)


@dataclass
class SimResult:
    """How a run ended. `job` is the job's dict as run (chassis and hub_dir resolved) plus the
    limits that applied, so a result read back later says exactly what produced it."""

    exit: str
    sim_ms: int
    wall_s: float
    pose: dict
    output: str
    error: str | None = None  # traceback text when exit == "error"
    real_time_factor: float | None = None
    peak_rss_mb: float | None = None
    job: dict = field(default_factory=dict)
    score: dict | None = None  # the world's scoring hook on the final state; None: no mission
    build_s: float | None = None  # of wall_s, building the physics at the first hardware use; None: never
    # The program's plot() samples, {"name", "value", "sim_ms"} each, in order; never in `output`.
    telemetry: list = field(default_factory=list)

    def to_json(self) -> str:
        return json.dumps(asdict(self))

    def summary(self) -> dict:
        """The fields a script collects across seeds (`sim run --json`, a sweep's rows)."""
        return {
            "seed": self.job.get("seed"),
            "exit": self.exit,
            "pose": self.pose,
            "score": self.score,
            "sim_s": self.sim_ms / 1000,
            "wall_s": self.wall_s,
            "build_s": self.build_s,
            "real_time_factor": self.real_time_factor,
            "error": self.error,
            "output": self.output,
            "telemetry": self.telemetry,
            "job": self.job,
        }


def report(result: SimResult, stream=None) -> None:
    """How the run ended, for a person: the error (if any), then one summary line, on `stream`
    (stderr by default: stdout carries the program's own output)."""
    stream = sys.stderr if stream is None else stream
    if result.error:
        stream.write(result.error if result.error.endswith("\n") else result.error + "\n")
    line = f"[{result.exit}] {result.sim_ms / 1000:.3f} s simulated in {result.wall_s:.2f} s"
    if result.real_time_factor is not None:
        line += f" ({result.real_time_factor}x real time)"
    pose = result.pose
    if pose:
        line += (
            f"; robot at x={pose['x_mm']:.1f} mm y={pose['y_mm']:.1f} mm "
            f"heading={pose['heading_deg']:.2f} deg"
        )
    stream.write(line + "\n")
    if result.score is not None:
        stream.write(f"score: {json.dumps(result.score)}\n")
    stream.flush()


def _check(ok, name, accepts):
    if not ok:
        raise JobError(f"sim job field {name}: give {accepts}")


def _whole(value):
    return isinstance(value, int) and not isinstance(value, bool)


def _number(value):
    return isinstance(value, (int, float)) and not isinstance(value, bool)


# --- the job's command-line options, for every front end ---------------------------------------


def seed_argument(text):
    """--seed: a whole number from 0 up (what the worlds' random generators accept)."""
    try:
        seed = int(text)
    except ValueError:
        seed = -1
    if seed < 0:
        raise argparse.ArgumentTypeError(f"{text!r}: give a whole number from 0 up")
    return seed


def limit_argument(text):
    """A limit in seconds or MB: a number from 0 up, 0 meaning no limit."""
    try:
        value = float(text)
    except ValueError:
        value = -1.0
    if not 0 <= value < math.inf:
        raise argparse.ArgumentTypeError(f"{text!r}: give a number from 0 up (0: no limit)")
    return value


def positive_argument(text: str) -> float:
    """Seconds or a speed factor: positive and finite (0, negatives, nan and inf are mistakes)."""
    value = finite_argument(text)
    if value <= 0:
        raise argparse.ArgumentTypeError(f"{text!r}: give a positive number, e.g. 2 or 0.5")
    return value


def finite_argument(text: str) -> float:
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not a number") from None
    if not math.isfinite(value):
        raise argparse.ArgumentTypeError(f"{text!r}: give a finite number")
    return value


def add_place_arguments(parser: argparse.ArgumentParser) -> None:
    """Where the robot is: world, chassis and start pose (metres and counter-clockwise yaw, as the
    manual's simulator chapter has them)."""
    parser.add_argument(
        "--world",
        default="empty",
        help=(
            f"World name ({WORLD_NAMES}), a world file (.toml), a mat image (.png, .jpg, .pdf, with "
            "--mat-size) or an MJCF file (.xml). Default: %(default)s."
        ),
    )
    parser.add_argument(
        "--mat-size",
        metavar="WxH",
        type=mat_size_argument,
        help="With --world IMAGE: the mat's printed size in mm (e.g. 2362x1143); an empty walled table.",
    )
    parser.add_argument(
        "--chassis",
        choices=CHASSIS_NAMES,
        help="Robot build. Default: the one whose motors the program constructs (st3032 otherwise).",
    )
    parser.add_argument(
        "--x", type=finite_argument, help="Start x on the mat, in metres. Default: the world's start."
    )
    parser.add_argument(
        "--y", type=finite_argument, help="Start y on the mat, in metres. Default: the world's start."
    )
    parser.add_argument(
        "--yaw",
        type=finite_argument,
        help="Start heading, degrees counter-clockwise from +x. Default: the world's start.",
    )


def add_seed_argument(parser: argparse.ArgumentParser) -> None:
    parser.add_argument(
        "--seed",
        type=seed_argument,
        default=0,
        help="Seed of the world's random layout (props, noise); one seed always gives one run. Default: 0.",
    )


def add_run_arguments(parser: argparse.ArgumentParser, single_run: bool = True) -> None:
    """How long and in what a run may run, and the sensor rig. single_run adds what only one run at
    a time can have: a pace for a person to watch, and a hub flash kept between runs."""
    if single_run:
        parser.add_argument(
            "--speed",
            type=positive_argument,
            help="Pace the run at this multiple of real time (1 = real time). Default: unpaced.",
        )
    parser.add_argument(
        "--duration",
        type=positive_argument,
        help=(
            "Simulated seconds before the run is cut off (exit time_limit). Default: the world file's "
            f"time_limit_s, else {DEFAULT_LIMIT_MS / 1000:g}."
        ),
    )
    parser.add_argument(
        "--wall-limit",
        type=limit_argument,
        metavar="SECONDS",
        help=(
            "Wall-clock seconds the run may take, 0 for no limit (it stops a loop that never lets "
            "simulated time pass). Default: --duration (twice --duration / --speed when paced), at "
            "least 10; none with --viewer."
        ),
    )
    parser.add_argument(
        "--cpu-limit",
        type=limit_argument,
        metavar="SECONDS",
        help="Processor seconds the run's process may use, 0 for no limit. Default: the wall limit + 5.",
    )
    parser.add_argument(
        "--memory-mb",
        type=int,
        default=DEFAULT_MEMORY_MB,
        metavar="MB",
        help="Memory (address space) of the run's process, 0 for no limit. Default: %(default)s.",
    )
    if single_run:
        parser.add_argument(
            "--hub-dir",
            metavar="DIR",
            help=(
                "The hub's flash for this run: the program's files (open('/qtr.cal', 'w')) land in DIR and "
                "stay for the next run. Default: a fresh temporary flash, removed after the run."
            ),
        )
    parser.add_argument(
        "--range-finder",
        choices=RANGE_FINDERS,
        default="vl53l0x",
        help="The laser range finder on the I2C mux's channel 7. Default: %(default)s.",
    )
    parser.add_argument(
        "--bare-0x29",
        choices=BARE_0X29_PARTS,
        help=(
            "Wire this one 0x29 part straight to the I2C bus (SDA 15, SCL 16) with no mux in between, as "
            "a build with a single colour sensor or range finder has it. Default: every 0x29 part behind "
            "the mux."
        ),
    )


def mat_size_argument(text: str) -> tuple[float, float]:
    from .world_file import mat_size_argument as parse

    try:
        return parse(text)
    except ValueError as exc:
        raise argparse.ArgumentTypeError(str(exc)) from None


def run_duration_s(args) -> float:
    """--duration, else the time limit of the world file --world names (a round's length), else the
    default. A world that cannot be read gives the default: its problems are told where it is built."""
    if args.duration is not None:
        return args.duration
    from .world_file import WorldFileError, open_world

    try:
        spec = open_world(args.world)
    except WorldFileError:
        spec = None
    if spec is not None and spec.time_limit_s is not None:
        return spec.time_limit_s
    return DEFAULT_LIMIT_MS / 1000


def sized_world(args) -> str:
    """--world, with --mat-size folded in as IMAGE@WxH: the one string a SimJob carries."""
    size = getattr(args, "mat_size", None)
    if size is None:
        return args.world
    return f"{args.world}@{size[0]:g}x{size[1]:g}"


def start_pose(args, world_start_mm_deg) -> tuple[float, float, float] | None:
    """(x_mm, y_mm, heading_deg) from the metre/yaw options, the world's start filling the gaps."""
    if args.x is None and args.y is None and args.yaw is None:
        return None
    x_mm, y_mm, heading_deg = world_start_mm_deg
    return (
        x_mm if args.x is None else args.x * 1000.0,
        y_mm if args.y is None else args.y * 1000.0,
        heading_deg if args.yaw is None else -args.yaw,
    )


def job_from_args(args, program: str) -> SimJob:
    """The SimJob the options parsed by add_*_arguments describe. Resolves the world (raising
    worlds.UnknownWorldError) only when a start option needs its start pose."""
    start = None
    if None not in (args.x, args.y, args.yaw):  # the whole pose given: no world to ask
        start = start_pose(args, (0.0, 0.0, 0.0))
    elif args.x is not None or args.y is not None or args.yaw is not None:
        from .worlds import resolve

        start = start_pose(args, resolve(sized_world(args)).start_mm_deg)
    return SimJob(
        program=str(program),
        world=sized_world(args),
        chassis=args.chassis,
        seed=getattr(args, "seed", 0),
        start_mm_deg=start,
        speed=getattr(args, "speed", None),
        limit_ms=int(round(run_duration_s(args) * 1000)),
        wall_limit_s=args.wall_limit,
        cpu_limit_s=args.cpu_limit,
        memory_mb=args.memory_mb,
        hub_dir=getattr(args, "hub_dir", None),
        range_finder=args.range_finder,
        bare_0x29=args.bare_0x29,
    )
