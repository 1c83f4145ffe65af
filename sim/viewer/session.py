"""`openbricks sim run PROGRAM --viewer`: run a program while a browser watches, run it again on request.

The program runs on the calling thread (the main thread, so Ctrl-C and the wall-clock watchdog work
as in a headless run), in a fresh Simulation each time: a restart is a new run of the same job, the
same world and seed, exactly as a second `sim run` would be. When a run ends the page keeps showing
where it ended until Restart is pressed or the terminal's Ctrl-C ends the session.
"""

from __future__ import annotations

import os
import sys
import time
from collections.abc import Callable

from ..job import STOPPED, SimJob, SimResult
from ..run import ProgramRun, with_source
from ..simulation import Simulation
from .viewer import DEFAULT_HOST, DEFAULT_PORT, SimViewer


def serve_run(
    job: SimJob,
    source: str | None = None,
    echo: Callable[[str], object] | None = None,
    host: str = DEFAULT_HOST,
    port: int = DEFAULT_PORT,
    keep_open: bool = True,
    on_ready: Callable[[str], object] | None = None,
    on_result: Callable[[SimResult], object] | None = None,
) -> SimResult:
    """Run `job` (its program file, or `source`) with the 3D view served at host:port.

    The job's speed is the real-time factor runs start at (the page can change it; None: real
    time, as a person watching expects). echo: where the program's output also goes (the
    terminal). on_ready(url) is called once the page can be opened; on_result(result) after every
    run. With keep_open=False the session ends with the first run; otherwise it ends on Ctrl-C (in
    the terminal), returning the last run's result.

    No wall-clock limit applies unless the job sets one: a paused or slowed run is meant to take
    long, and the page's Stop button ends a program that never lets simulated time pass.
    """
    job, source = with_source(job, source)
    with SimViewer(host, port, speed=1.0 if job.speed is None else job.speed) as viewer:
        if on_ready is not None:
            on_ready(viewer.url)

        def tee(text):
            viewer.write(text)
            if echo is not None:
                echo(text)

        while True:
            result = watched_run(viewer, job, source, tee)
            if on_result is not None:
                on_result(result)
            if viewer.restart_requested.is_set():
                viewer.output.clear()
                continue
            if result.exit == STOPPED and not viewer.stop_requested.is_set():
                return result  # Ctrl-C in the terminal: the person wants out, not a frozen page
            if not keep_open:
                return result
            try:
                viewer.wait_for_restart()
            except KeyboardInterrupt:
                return result
            viewer.output.clear()


def watched_run(viewer, job, source, echo, on_attached=None, plot_tag=None) -> SimResult:
    """One run of `job` shown and paced by `viewer`, in a fresh Simulation (its clock unpaced).

    on_attached(simulation) runs once the viewer shows it, before the program starts (the
    console's child sends telemetry and says it is ready from there). No wall-clock limit unless
    the job sets one: a watched run may be paused at will.
    """
    simulation = Simulation.for_job(job, paced=False)
    result = None
    try:
        run = ProgramRun(simulation, job.hub_dir)
        viewer.attach(simulation, stop=run.request_stop)
        try:
            if on_attached is not None:
                on_attached(simulation)
            result = run.run(
                source,
                os.path.basename(job.program),
                job.wall_limit(watched=True),
                echo,
                {**job.to_dict(), "viewer": True},
                plot_tag=plot_tag,
            )
        finally:
            viewer.detach(result)
    finally:
        simulation.close()
    return result


def launch(
    world="empty",
    chassis: str = "st3032",
    seed: int = 0,
    start_mm_deg=None,
    host: str = DEFAULT_HOST,
    port: int = DEFAULT_PORT,
    on_ready: Callable[[str], object] | None = None,
) -> int:
    """`openbricks sim preview`: the world with the robot standing at its start, served until Ctrl-C.

    world is an alias, an MJCF path or a World. Returns the command's exit status (0).
    """
    announce = print_url if on_ready is None else on_ready
    simulation = Simulation(world, chassis, seed, start_mm_deg)
    try:
        with SimViewer(host, port, controls=False) as viewer:
            viewer.show_still(simulation, "preview")
            announce(viewer.url)
            try:
                while True:
                    time.sleep(0.5)
            except KeyboardInterrupt:
                return 0
    finally:
        simulation.close()


def print_url(url: str) -> None:
    """The default announcement: where to point the browser, on stderr (stdout is the program's)."""
    print(f"3D view: {url}  (Ctrl-C to quit)", file=sys.stderr, flush=True)
