"""The simulator's command line (`openbricks sim ...`, or `python -m openbricks_sim.cli`).

    openbricks sim preview [--world W] [--x X] [--y Y] [--yaw DEG] [--headless] [--duration S] [--seed N]
    openbricks sim run SCRIPT [--world W] [--x X] [--y Y] [--yaw DEG] [--viewer] [--no-shim] [--seed N]
                               [--chassis C] [--speed F] [--duration S] [--json] [--hub-dir DIR]
                               [--range-finder PART] [--bare-0x29 PART]
    openbricks sim sweep SCRIPT --seeds 1-50 [--workers N | --dask tcp://host:8786] [--json] [--csv FILE]
                               [the run's options, as for sim run]

Positions follow the manual's simulator chapter: metres on the mat, yaw in degrees counter-clockwise
from +x (MuJoCo's convention); inside, the simulator works in millimetres with Pybricks' clockwise
heading. Without the `[sim]` extra (MuJoCo) every command prints how to install it, never a traceback.
MuJoCo and the worlds are imported only once a command needs them, so `--help` stays quick; a
contained `sim run` never imports them here at all (nor numpy): its child does, and this process
only waits for it, so a program that only prints ends as soon as the child has started and run it.
"""

from __future__ import annotations

import argparse
import importlib.util
import json
import os
import sys
import time

from openbricks_sim.job import (
    BARE_0X29_PARTS,  # noqa: F401 - kept in step with sensors.rig by a test
    CHASSIS_NAMES,  # noqa: F401
    INSTALL_HINT,
    RANGE_FINDERS,  # noqa: F401 - kept in step with sensors.rig by a test
    WORLD_NAMES,  # noqa: F401 - kept in step with worlds.WORLDS by a test
    JobError,
    UnknownWorldError,
    add_place_arguments,
    add_run_arguments,
    add_seed_argument,
    job_from_args,
    positive_argument,
    run_duration_s,
    sized_world,
    start_pose,
    world_file,
)
from openbricks_sim.program_robot import DEFAULT_CHASSIS

EXIT_OK = 0
EXIT_FAILED = 1
VIEWER_UNAVAILABLE = (
    "the 3D viewer is not available in this version yet; run without it (preview: --headless), or use "
    "--json and plot the result"
)


class SimCliError(Exception):
    """A user error: printed as one line, exit status 1."""


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="openbricks sim", description="The MuJoCo simulator: the same hub programs, no robot needed."
    )
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")

    preview = sub.add_parser(
        "preview",
        help="load a world with the robot and show it",
        description=(
            "Load a world with the robot on it and open the viewer to look around; with --headless, step "
            "the physics for --duration seconds instead and print where the robot ended (a smoke test)."
        ),
    )
    add_place_arguments(preview)
    add_seed_argument(preview)
    preview.add_argument(
        "--headless", action="store_true", help="Do not open a window; just step the physics."
    )
    preview.add_argument(
        "--duration",
        type=positive_argument,
        default=2.0,
        help="Seconds of physics with --headless. Default: %(default)s.",
    )

    run = sub.add_parser(
        "run",
        help="run a hub program against the simulated robot",
        description=(
            "Run SCRIPT as the hub would, against the simulated robot and world, and print its output. "
            "Without --viewer it runs headless, as fast as the computer allows (or at --speed)."
        ),
    )
    run.add_argument("script", metavar="SCRIPT", help="The program file, as you would run it on a hub.")
    add_place_arguments(run)
    add_seed_argument(run)
    run.add_argument("--viewer", action="store_true", help="Watch the run in the 3D viewer.")
    run.add_argument(
        "--no-shim",
        action="store_true",
        help=(
            "Run SCRIPT as plain host Python that drives the simulator itself: it gets `simulation` (an "
            "openbricks_sim Simulation of the chosen world) in its globals, and no hub modules are faked."
        ),
    )
    run.add_argument(
        "--json",
        action="store_true",
        help="Print one JSON object (exit reason, final pose, score, simulated and wall time), not text.",
    )
    add_run_arguments(run)

    sweep = sub.add_parser(
        "sweep",
        help="run a hub program over many seeds and summarise the scores",
        description=(
            "Run SCRIPT once per seed, exactly as `sim run` would (each in a contained process of its own), "
            "on a local pool or a Dask cluster, and print each seed's score, exit reason, simulated time and "
            "final pose with a summary: mean, median and lowest score, and the share of runs that ran to "
            "their end."
        ),
    )
    sweep.add_argument("script", metavar="SCRIPT", help="The program file, as you would run it on a hub.")
    sweep.add_argument(
        "--seeds", required=True, help="Seeds to run: a range 1-50, one seed 3, or a list 1,4,9 (mixes too)."
    )
    add_place_arguments(sweep)
    sweep.add_argument(
        "--workers",
        type=_whole_positive,
        help="Seeds run at a time on this computer. Default: one per CPU core.",
    )
    sweep.add_argument(
        "--dask",
        metavar="ADDRESS",
        help="Run the seeds on a Dask cluster instead: its scheduler's address, e.g. tcp://host:8786.",
    )
    sweep.add_argument(
        "--json", action="store_true", help="Print one JSON object: a row per seed and the summary."
    )
    sweep.add_argument("--csv", metavar="FILE", help="Also write a row per seed to FILE as CSV.")
    add_run_arguments(sweep, single_run=False)
    return parser


def _whole_positive(text: str) -> int:
    try:
        value = int(text)
    except ValueError:
        value = 0
    if value < 1:
        raise argparse.ArgumentTypeError(f"{text!r}: give a whole number from 1 up")
    return value


def main(argv: list[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    if args.command is None:
        parser.print_help()
        return EXIT_OK
    args.world = sized_world(args)  # IMAGE@WxH from --world IMAGE --mat-size WxH
    args.mat_size = None
    if args.command in ("run", "sweep"):
        args.duration = run_duration_s(args)  # a world file's round length when --duration is not given
    try:
        _require_mujoco(loaded_here=args.command != "run" or args.no_shim or args.viewer)
        if args.command == "preview":
            return _preview(args)
        if args.command == "sweep":
            return _sweep(args)
        return _run(args)
    except SimCliError as exc:
        print(f"openbricks sim {args.command}: error: {exc}", file=sys.stderr)
        return EXIT_FAILED


def _require_mujoco(loaded_here: bool) -> None:
    """The install hint unless MuJoCo is there. A command that loads it in this process imports it
    to find out; a contained run only looks for it, since only its child needs it (and the child
    gives the same hint when it is there but does not load)."""
    if not loaded_here:
        if importlib.util.find_spec("mujoco") is None:
            raise SimCliError(f"{INSTALL_HINT} (No module named 'mujoco')")
        return
    try:
        import mujoco  # noqa: F401
    except ImportError as exc:
        raise SimCliError(f"{INSTALL_HINT} ({exc})") from None


def _start_pose(args, world) -> tuple[float, float, float] | None:
    return start_pose(args, world.start_mm_deg)


def _world(name: str):
    from openbricks_sim.worlds import resolve

    try:
        return resolve(name)
    except UnknownWorldError as exc:
        raise SimCliError(str(exc)) from None


def _check_world(name: str) -> None:
    """A world name or file refused as _world would, without MuJoCo: whether MuJoCo can load an MJCF
    file is for the child that builds the world to say."""
    try:
        world_file(name)
    except UnknownWorldError as exc:
        raise SimCliError(str(exc)) from None


def _viewer_launcher():
    """The viewer's entry point, or None while the viewer has not been built."""
    if importlib.util.find_spec("openbricks_sim.viewer") is None:
        return None
    try:
        viewer = importlib.import_module("openbricks_sim.viewer")
    except ImportError as exc:  # viser or mjviser missing: the message says how to install them
        raise SimCliError(str(exc)) from None
    return getattr(viewer, "launch", None)


def _pose_dict(pose) -> dict:
    return {
        "x_mm": round(pose.x_mm, 3),
        "y_mm": round(pose.y_mm, 3),
        "heading_deg": round(pose.heading_deg, 3),
    }


def _preview(args) -> int:
    world = _world(args.world)
    if not args.headless:
        launch = _viewer_launcher()
        if launch is None:
            raise SimCliError(VIEWER_UNAVAILABLE)
        return (
            launch(
                world=world,
                chassis=args.chassis or DEFAULT_CHASSIS,
                seed=args.seed,
                start_mm_deg=_start_pose(args, world),
            )
            or 0
        )
    from openbricks_sim.physics import Physics

    physics = Physics(world, args.chassis or DEFAULT_CHASSIS, args.seed, _start_pose(args, world))
    try:
        started = time.perf_counter()
        physics.step(int(round(args.duration * 1000)))
        wall_s = time.perf_counter() - started
        pose = physics.pose()
    finally:
        physics.close()
    print(
        f"{world.alias}: {args.duration:g} s of physics in {wall_s:.2f} s; robot at x={pose.x_mm:.1f} mm "
        f"y={pose.y_mm:.1f} mm heading={pose.heading_deg:.2f} deg"
    )
    return EXIT_OK


def _program(path: str):
    """(path, text) of the program file, refused before any world is built if it is not one."""
    if os.path.isdir(path):
        raise SimCliError(f"{path} is a folder: give the program's .py file")
    if not os.path.isfile(path):
        raise SimCliError(f"{path}: no such program file")
    try:
        with open(path, encoding="utf-8") as program:
            source = program.read()
    except UnicodeDecodeError as exc:
        raise SimCliError(f"{path} is not UTF-8 text ({exc.reason} at byte {exc.start})") from None
    _check_syntax(source, os.path.basename(path))
    return path, source


def _run(args) -> int:
    script, source = _program(args.script)
    if args.viewer and _viewer_launcher() is None:
        raise SimCliError(VIEWER_UNAVAILABLE)
    if args.no_shim:
        return _run_unshimmed(args, _world(args.world), script, source)
    _check_world(args.world)
    from openbricks_sim.run_flash import HubDirError, prepare_hub_dir

    try:
        prepare_hub_dir(args.hub_dir)
    except HubDirError as exc:
        raise SimCliError(str(exc)) from None
    return _run_contained(args, script)


def _check_syntax(source: str, filename: str) -> None:
    """A syntax error as Python shows one (file, line, the line, a caret), before any world is built."""
    if "\x00" in source:
        raise SimCliError(
            f"{filename} contains a NUL byte (0x00), which program text never does: is it binary?"
        )
    try:
        compile(source, filename, "exec", dont_inherit=True)
    except SyntaxError as exc:
        import traceback

        raise SimCliError("".join(traceback.format_exception_only(exc)).rstrip()) from None


def _sweep(args) -> int:
    """Seeds run in contained child processes (sweep.py); this process only waits and reports."""
    from openbricks_sim.sweep import SweepError, parse_seeds
    from openbricks_sim.sweep_report import run_sweep

    script, source = _program(args.script)
    _world(args.world)
    if args.dask and args.workers:
        raise SimCliError(
            "--workers is for the local pool; a Dask cluster runs as many seeds as it has workers"
        )
    try:
        seeds = parse_seeds(args.seeds)
        job = job_from_args(args, str(script))
        return run_sweep(job, seeds, source, args)
    except (SweepError, JobError) as exc:
        raise SimCliError(str(exc)) from None


def _run_contained(args, script) -> int:
    """The program runs in a child process under limits (run_process.py); this process waits, passes
    Ctrl-C on, and prints the JSON summary for --json (the child prints text reports itself)."""
    from openbricks_sim.job import report
    from openbricks_sim.run_process import run_in_child

    try:
        job = job_from_args(args, str(script))  # a start option naming part of the pose asks the world
    except (JobError, UnknownWorldError) as exc:
        raise SimCliError(str(exc)) from None
    from openbricks_sim import shared_server

    forker = shared_server.connect()  # a warm server of this installation, when one runs
    try:
        result, status = run_in_child(job, viewer=args.viewer, silent=args.json, forker=forker)
    finally:
        if forker is not None:
            forker.close()
        else:
            shared_server.start_in_background()  # for the runs after this one
    if args.json:
        print(json.dumps(result.summary()))
    elif "limits" not in result.job:  # the child ended before it could report: say why here
        report(result)
    return status


def _run_unshimmed(args, world, script, source) -> int:
    """--no-shim: the script is host Python with `simulation` in its globals; what it raises is its result."""
    import traceback

    from openbricks_sim.simulation import Simulation

    simulation = Simulation(
        world,
        args.chassis or DEFAULT_CHASSIS,
        args.seed,
        _start_pose(args, world),
        speed=args.speed,
        limit_ms=int(args.duration * 1000),
        range_finder=args.range_finder,
        bare_0x29=args.bare_0x29,
    )
    exit_reason, error = "finished", None
    started = time.perf_counter()
    try:
        code = compile(source, str(script), "exec")
        exec(code, {"__name__": "__main__", "__file__": str(script), "simulation": simulation})
    except SystemExit:
        pass
    except BaseException as exc:  # noqa: BLE001 - the script's own failure is what we report
        if type(exc).__name__ == "SimTimeLimit":
            exit_reason = "time_limit"
        else:
            exit_reason, error = "error", "".join(traceback.format_exception(exc))
    finally:
        wall_s = time.perf_counter() - started
        pose = simulation.physics.pose()
        sim_ms = simulation.physics.now_ms
        simulation.close()
    summary = {
        "exit": exit_reason,
        "pose": _pose_dict(pose),
        "score": None,
        "sim_s": sim_ms / 1000,
        "wall_s": round(wall_s, 4),
        "error": error,
    }
    if args.json:
        print(json.dumps(summary))
    else:
        if error:
            sys.stderr.write(error)
        print(f"[{exit_reason}] {sim_ms / 1000:.3f} s simulated in {wall_s:.2f} s", file=sys.stderr)
    return EXIT_OK if exit_reason in ("finished", "time_limit") else EXIT_FAILED


if __name__ == "__main__":
    sys.exit(main())
