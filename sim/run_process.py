"""`openbricks sim run`'s side of a run: the program runs in a child process, never in the CLI's.

    result, status = run_in_child(SimJob("square.py", world="wro"), quiet=True)

The child runs `python -m openbricks_sim.run` (run.py), which fences itself in (limits.contain:
memory, CPU time, file size, no new processes), runs the program, prints its output and report
on the terminal it shares with us, and sends its RunResult as JSON over a pipe. It is a fork of
this process when that is safe (forked.py: one thread, an OS with fork()), so a run starts from
what the CLI has imported instead of a new interpreter's start-up; a new interpreter otherwise.
This side:

- starts it in a session of its own with no stdin, so the terminal's Ctrl-C (and a SIGTERM or
  SIGHUP to the CLI) reaches only the CLI, which passes exactly one interrupt on: the program
  stops, the child still reports how far it got; a second Ctrl-C kills the child;
- backs up the child's own wall-clock limit: a child still alive GRACE_S after it is killed,
  whatever the program did to its signals;
- turns a child that died without a result (the CPU limit's SIGKILL, a crash) into a result
  with one line saying why.
"""

from __future__ import annotations

import functools
import json
import os
import signal
import subprocess
import sys
import threading
import time

from .forked import ForkServerError, can_fork, fork_child
from .job import CPU_LIMIT, ERROR, EXIT_STATUS, INSTALL_HINT, STOPPED, WALL_LIMIT, SimJob, SimResult

GRACE_S = 10.0  # start-up (imports, the world's build) plus the child's own wall-limit handling
FORWARDED_SIGNALS = (signal.SIGINT, signal.SIGTERM, signal.SIGHUP)
# A spawned child's program (where this process cannot fork): child_main() in a new interpreter.
CHILD_MAIN = (
    "import sys\nfrom openbricks_sim.run_process import child_main\nsys.exit(child_main(sys.argv[1:]))\n"
)


def child_main(child_args: list[str]) -> int:
    """The child's side: `python -m openbricks_sim.run`, except that a Ctrl-C while the simulator
    still imports ends it quietly instead of with a traceback of the imports, and a MuJoCo that is
    there but does not load (a missing system library) is the run's result with the install hint:
    the CLI only looked for MuJoCo, it did not import it."""
    try:
        from .run import main
    except KeyboardInterrupt:
        return 130
    except ImportError as exc:
        return report_import_error(exc, child_args)
    return main(child_args)


def run_in_child(
    job: SimJob, viewer=False, silent=False, quiet=False, stop=None, forker=None
) -> tuple[SimResult, int]:
    """Run `job` in `python -m openbricks_sim.run --job JSON --result-fd N`; (its SimResult, exit status).

    viewer: serve the 3D view (the child runs until interrupted). By default the program's output
    and the report go to the terminal we share, as a run on the hub would; silent: the child prints
    neither (they are in the result: `sim run --json`); quiet: silent, and whatever else the child
    writes is discarded too (a sweep's hundred children on one terminal).
    Off the main thread (a sweep's worker) no signal is forwarded: Python handles signals only there;
    setting `stop` (a threading.Event) stops the program instead, as a Ctrl-C would. forker: a
    fork_server.ForkServer to start the child from (a sweep's, warm), instead of a fork of this process.
    """
    wall_limit_s = job.wall_limit(watched=viewer)
    cpu_limit_s = job.cpu_limit(watched=viewer)
    child_args = ["--job", job.to_json()]
    if viewer:
        child_args.append("--viewer")
    if silent or quiet:
        child_args.append("--json")
    interrupts = []
    children = []
    on_main_thread = threading.current_thread() is threading.main_thread()

    def interrupt(signum, _frame):
        interrupts.append(signum)
        for child in children:
            if child.poll() is None:
                child.send_signal(signal.SIGINT) if len(interrupts) == 1 else child.kill()

    # Installed before the child starts: it then begins with SIGINT at its default (a Python handler
    # is reset by exec, an ignored signal would stay ignored) and sees the interrupt we pass on.
    previous = {}
    if on_main_thread:
        previous = {signum: signal.signal(signum, interrupt) for signum in FORWARDED_SIGNALS}
    read_end, write_end = os.pipe()
    sys.stdout.flush()
    sys.stderr.flush()
    started = time.monotonic()
    killed_for_time = False
    try:
        try:
            child = _start_child(child_args, write_end, quiet, forker)
        finally:
            os.close(write_end)
        children.append(child)
        if interrupts:
            child.send_signal(signal.SIGINT)
        chunks = []
        reader = threading.Thread(target=_read_all, args=(read_end, chunks), daemon=True)
        reader.start()
        killed_for_time = _wait(child, None if not wall_limit_s else wall_limit_s + GRACE_S, stop, interrupts)
    finally:
        for signum, handler in previous.items():
            signal.signal(signum, handler)
    reader.join(timeout=5)
    wall_s = round(time.monotonic() - started, 4)
    text = b"".join(chunks).decode("utf-8", "replace").strip()
    if text:
        result = SimResult(**json.loads(text))
    else:
        result = _lost_result(
            child.returncode, wall_s, killed_for_time, bool(interrupts), wall_limit_s, cpu_limit_s, quiet
        )
    if interrupts and result.exit == STOPPED:
        return result, EXIT_STATUS[STOPPED]
    return result, EXIT_STATUS.get(result.exit, 1)


def _start_child(child_args, write_end, quiet, forker):
    """The child: from `forker` (a warm ForkServer) if given, else a fork of this process when that is
    safe, else a new interpreter; each runs child_main() with no stdin, in a session of its own, the
    result pipe's write end its only descriptor beyond 0, 1 and 2 (its fd 3 when forked)."""
    if forker is not None or can_fork():
        devnull = os.open(os.devnull, os.O_RDWR)
        stdio = {"stdin": devnull, "stdout": devnull if quiet else None, "stderr": devnull if quiet else None}
        args = [*child_args, "--result-fd", "3"]
        try:
            if forker is not None:
                try:
                    return forker.start("run", args, **stdio, pass_fds=(write_end,))
                except ForkServerError:  # the server is gone: this child starts cold instead
                    pass
            if can_fork():
                return fork_child(functools.partial(child_main, args), **stdio, extra_fds=(write_end,))
        finally:
            os.close(devnull)
    return subprocess.Popen(
        [sys.executable, "-c", CHILD_MAIN, *child_args, "--result-fd", str(write_end)],
        stdin=subprocess.DEVNULL,
        stdout=subprocess.DEVNULL if quiet else None,
        stderr=subprocess.DEVNULL if quiet else None,
        pass_fds=(write_end,),
        start_new_session=True,
    )


def _wait(child, timeout_s, stop, interrupts) -> bool:
    """Wait for the child; True if it outlived timeout_s and was killed. A set `stop` interrupts it."""
    deadline = None if timeout_s is None else time.monotonic() + timeout_s
    while True:
        slice_s = None if stop is None else 0.2
        if deadline is not None:
            left = max(0.0, deadline - time.monotonic())
            slice_s = left if slice_s is None else min(slice_s, left)
        try:
            child.wait(timeout=slice_s)
            return False
        except subprocess.TimeoutExpired:
            pass
        if deadline is not None and time.monotonic() >= deadline:
            child.kill()
            child.wait()
            return True
        if stop is not None and stop.is_set() and not interrupts:
            interrupts.append(signal.SIGINT)
            child.send_signal(signal.SIGINT)


def _read_all(fd, chunks):
    with os.fdopen(fd, "rb") as pipe:
        while True:
            chunk = pipe.read(65536)
            if not chunk:
                return
            chunks.append(chunk)


def _lost_result(returncode, wall_s, killed_for_time, interrupted, wall_limit_s, cpu_limit_s, quiet):
    """The result of a child that ended without sending one: what ended it, in one line."""
    if killed_for_time:
        exit_reason = WALL_LIMIT
        error = (
            f"wall-clock limit: the program was still running {wall_limit_s:g} s (--wall-limit) plus "
            f"{GRACE_S:g} s of grace after it should have stopped, and its process was killed: a loop "
            "that never sleeps and catches every interrupt"
        )
    elif returncode in (-signal.SIGKILL, -signal.SIGXCPU) and cpu_limit_s and not interrupted:
        exit_reason = CPU_LIMIT
        error = (
            f"CPU-time limit: the run's process used its {cpu_limit_s:g} s of processor time "
            "(--cpu-limit) and was killed: a loop that never lets simulated time pass, or a very long run"
        )
    elif interrupted:
        exit_reason = STOPPED
        error = "stopped: the run's process ended before it could report"
    else:
        exit_reason = ERROR
        how = f"was killed by signal {-returncode}" if returncode < 0 else f"exited with status {returncode}"
        where = "" if quiet else " (its messages are above)"
        error = f"the simulator's process {how} without a result{where}"
    return SimResult(exit=exit_reason, sim_ms=0, wall_s=wall_s, pose={}, output="", error=error)


def report_import_error(exc: ImportError, child_args: list[str]) -> int:
    """In a child whose simulator failed to import: a MuJoCo that does not load is the run's result,
    the install hint with MuJoCo's own reason, sent back like any other; anything else is a bug,
    raised as it is."""
    try:
        import mujoco  # noqa: F401 - the import is the question
    except ImportError as mujoco_exc:
        reason = mujoco_exc
    else:
        raise exc
    job = json.loads(child_args[child_args.index("--job") + 1])
    result = SimResult(
        exit=ERROR, sim_ms=0, wall_s=0.0, pose={}, output="", error=f"{INSTALL_HINT} ({reason})", job=job
    )
    fd = int(child_args[child_args.index("--result-fd") + 1])
    with os.fdopen(fd, "w", encoding="utf-8") as out:
        out.write(result.to_json() + "\n")
    return EXIT_STATUS[ERROR]
