"""Run a hub program against a simulated robot and report what happened.

    result = run_program("square.py", world="empty", chassis="st3032", limit_ms=60_000)
    print(result.exit, result.pose, result.output)

The program runs unchanged: as `__main__`, with its own globals, importing
`machine`, `time`, `openbricks...` from the simulator's shim. Its files are
the hub's: `open("/qtr.cal", "w")` writes to the run's hub flash (run_flash.py),
a fresh temporary directory per run unless `hub_dir` names one to keep. It ends when
it returns, raises, calls sys.exit() or machine.reset(), reaches the
simulated time limit, exceeds the wall-clock limit (a loop that never lets
time pass), or is stopped from another thread (request_stop()).

The shim patches process-wide state (sys.modules, stdout), and user code must
never run in the CLI's process, so programs run in a process of their own:
`python -m openbricks_sim.run PROGRAM --json` does exactly that, fenced in
by limits.contain() (memory, CPU time, file size, no new processes), and
prints the result as JSON; `openbricks sim run` starts it (run_process.py).
"""

import _thread
import argparse
import contextlib
import functools
import gc
import importlib
import io
import json
import os
import secrets
import signal
import sys
import threading
import time
from dataclasses import replace

from openbricks.host_protocol import FRAME_PREFIX, parse_plot

from . import limits
from .clock import SimStopped, SimTimeLimit
from .job import (
    CPU_LIMIT,
    ERROR,
    EXIT_STATUS,
    FINISHED,
    MEMORY_LIMIT,
    RESET,
    STOPPED,
    TIME_LIMIT,
    WALL_LIMIT,
    JobError,
    SimJob,
    SimResult,
    SimulatorUnavailable,
    UnknownWorldError,
    add_place_arguments,
    add_run_arguments,
    add_seed_argument,
    job_from_args,
    report,
)
from .limits import CpuLimitExceeded, contain
from .program_robot import ProgramRobot, infer_chassis
from .python_cost import PythonCost
from .run_flash import HubDirError, RunFlash, prepare_hub_dir
from .shim import Shim
from .simulation import Simulation


class _Output(io.TextIOBase):
    """Collects what the program prints, and passes each write on to `echo` (live output) if given.

    With `frame_start` (the run's own plot tag), a line that starts with it is a plot() frame: read with
    the hub protocol's parse_plot, its sample joins `samples` at the simulated time `now_ms()` and is
    echoed as a hub run without a console prints it (`plot: name = value`), but is not output. Text
    that may still become a frame waits for its line's end; any other text passes at once.
    """

    def __init__(self, echo=None, frame_start=None, now_ms=None):
        self._parts = []
        self._echo = echo
        self._frame = frame_start
        self._now_ms = now_ms
        self._line = ""  # the held start of a line that may be a frame
        self._line_start = True
        self.samples = []

    def writable(self):
        return True

    def write(self, text):
        if self._frame is None:
            self._pass(text)
            return len(text)
        rest = self._line + text
        self._line = ""
        while rest:
            if not self._line_start:
                end = rest.find("\n") + 1 or len(rest)
                self._pass(rest[:end])
                rest = rest[end:]
                continue
            end = rest.find("\n") + 1
            if end == 0:
                if self._frame.startswith(rest) or rest.startswith(self._frame):
                    self._line = rest  # may be a frame: wait for the line's end
                else:
                    self._pass(rest)
                break
            self._take_line(rest[:end])
            rest = rest[end:]
        return len(text)

    def _take_line(self, line):
        parsed = None
        if line.startswith(self._frame):
            kind, _, payload = line[len(self._frame) :].partition(" ")
            parsed = parse_plot(payload) if kind == "plot" else None
        if parsed is None:
            self._pass(line)
            return
        name, value = parsed
        self.samples.append({"name": name, "value": value, "sim_ms": self._now_ms()})
        if self._echo is not None:
            shown = json.dumps(int(value) if value.is_integer() else value)  # as the console's CLI shows it
            self._echo(f"plot: {name} = {shown}\n")

    def _pass(self, text):
        self._line_start = text.endswith("\n")
        self._parts.append(text)
        if self._echo is not None:
            self._echo(text)

    def close_line(self):
        """The run ended: a held line start is output after all."""
        if self._line:
            self._pass(self._line)
            self._line = ""

    def text(self):
        return "".join(self._parts)


class ProgramRun:
    """One run; request_stop() may be called from another thread while run() executes.

    `hub_dir` is the hub's flash (its root directory); None gives each run() a fresh temporary one.
    """

    def __init__(self, simulation, hub_dir=None):
        self.simulation = simulation
        self.hub_dir = prepare_hub_dir(hub_dir)
        self._wall_expired = False

    def request_stop(self):
        self.simulation.clock.request_stop()

    def run(
        self, source, filename="main.py", wall_limit_s=None, echo=None, job=None, plot_tag=None
    ) -> SimResult:
        """`plot_tag`: the nonce of a console that watches the run, which then takes the program's
        plot() frames for telemetry as it does a hub's; None: the run tags and reads them itself, into
        the result's telemetry."""
        sim = self.simulation
        code = compile(source, filename, "exec")
        if plot_tag is None:
            plot_tag = secrets.token_hex(4)
            output = _Output(echo, f"{FRAME_PREFIX}{plot_tag} ", sim.clock.now_ms)
        else:
            output = _Output(echo)
        watchdog = None
        if wall_limit_s is not None:
            watchdog = threading.Timer(wall_limit_s, self._wall_limit_reached)
            watchdog.daemon = True
        exit_reason, error = FINISHED, None
        saved_streams = sys.stdout, sys.stderr
        started = time.perf_counter()
        try:
            with (
                _interruptible(),
                Shim(sim) as shim,
                RunFlash(self.hub_dir) as flash,
                ProgramRobot(sim),
                PythonCost(sim.clock),
            ):
                sim.on_build = functools.partial(_building, shim, sim.clock)
                sys.stdout = sys.stderr = output
                # On the runtime the program imports (the shim's fresh one).
                importlib.import_module("openbricks.tools")._plot_tag[0] = plot_tag
                # What is built so far (the runtime's shim, MuJoCo if a caller built it) out of the
                # collector's reach: each collection the program's allocations start no longer walks
                # all of it again. The physics, built at the first hardware use, joins it then.
                gc.freeze()
                if watchdog is not None:
                    watchdog.start()
                try:
                    exec(code, flash.program_globals(filename))
                except SimTimeLimit:
                    exit_reason = TIME_LIMIT
                except SimStopped:
                    exit_reason = STOPPED
                except KeyboardInterrupt:
                    exit_reason = WALL_LIMIT if self._wall_expired else STOPPED
                except CpuLimitExceeded:
                    exit_reason = CPU_LIMIT
                except SimulatorUnavailable as exc:
                    exit_reason, error = ERROR, f"{exc}\n"
                except MemoryError as exc:
                    exit_reason = MEMORY_LIMIT
                    error = flash.python.traceback.format(exc, program=True)
                except SystemExit:
                    exit_reason = RESET if sim.board.reset_requested else FINISHED
                except BaseException as exc:  # noqa: BLE001 - whatever the program raised is its result
                    exit_reason = ERROR
                    error = flash.python.traceback.format(exc, program=True)
                finally:
                    if watchdog is not None:
                        watchdog.cancel()
                    sys.stdout, sys.stderr = saved_streams
        finally:
            sys.stdout, sys.stderr = saved_streams
        output.close_line()
        wall_s = time.perf_counter() - started
        if exit_reason in LIMIT_MESSAGES:
            error = (error or "") + LIMIT_MESSAGES[exit_reason](wall_limit_s, sim.clock.now_ms()) + "\n"
        sim.on_build = None
        sim_ms = sim.clock.now_ms()
        pose, score = _final_pose_and_score(sim)
        return SimResult(
            exit=exit_reason,
            sim_ms=sim_ms,
            wall_s=round(wall_s, 4),
            pose=pose,
            build_s=sim.build_s,
            output=output.text(),
            telemetry=output.samples,
            error=error,
            real_time_factor=round(sim_ms / 1000 / wall_s, 2) if wall_s > 0 else None,
            peak_rss_mb=_peak_rss_mb(),
            job=job or {},
            score=score,
        )

    def _wall_limit_reached(self):
        self._wall_expired = True
        _thread.interrupt_main()


def _final_pose_and_score(sim) -> tuple[dict, dict | None]:
    """Where the robot ended and the world's score. A program that never touched the hardware on the
    empty world ends where it stood, with no MuJoCo built for it; no pose when MuJoCo would not load."""
    resting = sim.resting_pose_mm_deg()
    if resting is not None:
        x_mm, y_mm, heading_deg = resting
        return {"x_mm": x_mm, "y_mm": y_mm, "heading_deg": heading_deg}, None
    try:
        physics = sim.physics
    except SimulatorUnavailable:
        return {}, None
    from .worlds import final_state

    pose = physics.pose()
    scoring = physics.world.score
    score = scoring(final_state(physics.model, physics.data)) if scoring else None
    return {"x_mm": pose.x_mm, "y_mm": pose.y_mm, "heading_deg": pose.heading_deg}, score


@contextlib.contextmanager
def _building(shim, clock):
    """Around the physics' build in the middle of a program: the host's own modules (the program's
    `time` is the shim's) while MuJoCo and the world import, no Python-time charge for it (it is
    the simulator's work, not the hub's), and what it built frozen out of the collector's reach."""
    cost = clock.python_cost
    counting = cost is not None and cost.counting
    if counting:
        cost.pause()
    try:
        with shim.host_modules():
            yield
        gc.freeze()
    finally:
        if counting:
            cost.resume()


@contextlib.contextmanager
def _interruptible():
    """Let a stop reach the program as KeyboardInterrupt while it runs.

    The wall-clock watchdog and the viewer's stop interrupt the main thread with
    `_thread.interrupt_main()`, which does nothing while SIGINT is ignored, and a process
    started in the background of a script inherits it ignored: a program that never lets time
    pass would then outlive every limit.
    """
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    previous = signal.signal(signal.SIGINT, signal.default_int_handler)
    try:
        yield
    finally:
        signal.signal(signal.SIGINT, previous)


def _wall_limit_message(wall_limit_s, sim_ms):
    return (
        f"wall-clock limit: the program ran {wall_limit_s:g} s of wall-clock time (--wall-limit) and "
        f"simulated time reached only {sim_ms} ms: a loop that never sleeps, waits on a device or reads "
        "the clock keeps simulated time from passing (add time.sleep_ms() to the loop)"
    )


def _cpu_limit_message(_wall_limit_s, sim_ms):
    cpu_s = limits.applied.get("cpu_s")
    return (
        f"CPU-time limit: the run's process used its {cpu_s or 0:g} s of processor time (--cpu-limit) at "
        f"{sim_ms} ms of simulated time: a loop that never lets simulated time pass, or a very long run "
        "(raise --cpu-limit)"
    )


def _memory_limit_message(_wall_limit_s, _sim_ms):
    memory_mb = limits.applied.get("memory_mb")
    size = f"its {memory_mb} MB of" if memory_mb else "its"
    return (
        f"memory limit: the program ran out of {size} memory (--memory-mb); a hub has far less, so "
        "look for a list or buffer that keeps growing"
    )


LIMIT_MESSAGES = {
    WALL_LIMIT: _wall_limit_message,
    CPU_LIMIT: _cpu_limit_message,
    MEMORY_LIMIT: _memory_limit_message,
}


def with_source(job: SimJob, source=None) -> tuple[SimJob, str]:
    """(the job with its chassis resolved, the program's text): read from job.program unless given,
    the build the program's motor drivers describe when the job names none."""
    if source is None:
        with open(job.program, encoding="utf-8") as f:
            source = f.read()
    if job.chassis is None:
        job = replace(job, chassis=infer_chassis(source))
    return job, source


def run_job(job: SimJob, source=None, echo=None, watched=False) -> SimResult:
    """Run `job` in this process (only in a process of its own: the shim patches process-wide state).

    source: the program's text (None: read job.program). echo(text): live output. The chassis the
    program describes and the hub flash are resolved here and recorded in the result's job.
    """
    job, source = with_source(job, source)
    job = replace(job, hub_dir=prepare_hub_dir(job.hub_dir))
    sim = Simulation.for_job(job)
    try:
        return ProgramRun(sim, job.hub_dir).run(
            source, os.path.basename(job.program), job.wall_limit(watched), echo, job.to_dict()
        )
    finally:
        sim.close()


def run_program(program, source=None, echo=None, **fields) -> SimResult:
    """run_job(SimJob(program, **fields)): the keyword form, for scripts and tests."""
    return run_job(SimJob(os.fspath(program), **fields), source, echo)


def _peak_rss_mb():
    """This process's peak resident memory, in MB.

    Linux's VmHWM belongs to the running image; getrusage's maxrss would also count the parent's
    memory at fork time, which makes a small child spawned by a big process look big.
    """
    try:
        with open("/proc/self/status", encoding="ascii") as status:
            for line in status:
                if line.startswith("VmHWM:"):
                    return round(int(line.split()[1]) / 1024, 1)
    except OSError:
        pass
    try:
        import resource
    except ImportError:  # Windows
        return None
    peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    return round(peak / (1024 * 1024 if sys.platform == "darwin" else 1024), 1)


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(
        prog="python -m openbricks_sim.run",
        description="Run a hub program in the simulator, in this process, fenced in by limits.",
    )
    parser.add_argument("program", nargs="?", help="the program file, as you would run it on the hub")
    add_place_arguments(parser)
    add_seed_argument(parser)
    add_run_arguments(parser)
    parser.add_argument("--job", help="the whole job as JSON (SimJob.to_json()), instead of the options")
    parser.add_argument(
        "--viewer",
        action="store_true",
        help="serve the 3D view and run until interrupted (no wall-clock or CPU limit by default)",
    )
    parser.add_argument("--json", action="store_true", help="print the result as one JSON object")
    parser.add_argument(
        "--result-fd", type=int, help="write the JSON result to this file descriptor instead of stdout"
    )
    args = parser.parse_args(argv)
    try:
        if args.job is not None:
            job = SimJob.from_dict(json.loads(args.job))
        elif args.program is None:
            parser.error("give the program file (or --job)")
        else:
            job = job_from_args(args, args.program)
        prepare_hub_dir(job.hub_dir)
    except (HubDirError, JobError, ValueError) as exc:
        parser.error(str(exc))
    result_out = os.fdopen(args.result_fd, "w", encoding="utf-8") if args.result_fd is not None else None
    wall_s = job.wall_limit(watched=args.viewer)
    cpu_s = job.cpu_limit(watched=args.viewer)
    contain(memory_mb=job.memory_mb, cpu_s=cpu_s)
    # Ctrl-C reaches us as the CLI's forwarded SIGINT: a KeyboardInterrupt, even when this process
    # was started with SIGINT ignored (a background job of a script).
    signal.signal(signal.SIGINT, signal.default_int_handler)
    stdout = sys.stdout
    echo = None if args.json else _echo_to(stdout)
    on_result = None if args.json else report
    try:
        if args.viewer:
            from .viewer import print_url, serve_run

            result = serve_run(job, echo=echo, on_ready=print_url, on_result=on_result)
        else:
            result = run_job(job, echo=echo)
            if on_result is not None:
                on_result(result)
    except UnknownWorldError as exc:  # an MJCF file MuJoCo cannot load: the CLI only saw it exists
        result = SimResult(
            exit=ERROR, sim_ms=0, wall_s=0.0, pose={}, output="", error=str(exc), job=job.to_dict()
        )
        if on_result is not None:
            on_result(result)
    signal.signal(signal.SIGXCPU, signal.SIG_IGN)  # the result is out: only the hard limit remains
    result.job["limits"] = {"wall_s": wall_s, "cpu_s": cpu_s, "memory_mb": job.memory_mb}
    if result_out is not None:
        with result_out:
            result_out.write(result.to_json() + "\n")
    elif args.json:
        stdout.write(result.to_json() + "\n")
    return EXIT_STATUS[result.exit]


def _echo_to(stream):
    """Live output to `stream`, bound now: during the run sys.stdout is the run's own collector."""

    def echo(text):
        stream.write(text)
        stream.flush()

    return echo


if __name__ == "__main__":
    sys.exit(main())
