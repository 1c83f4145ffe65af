"""A sim run as the console daemon runs it: one child process per run, never the daemon's own.

    python -m openbricks_sim.console_job SPEC.json

SPEC.json is `{"job": SimJob.to_dict(), "recording": PATH, "plot_tag": NONCE}`: the one job definition
every front end runs, where to write the recording, and the nonce the program's plot() tags its frames
with, so the daemon takes them for telemetry with the parser it uses for a hub's output. The process
fences itself in (limits.contain: memory, CPU time, no new processes), serves the run's 3D view on
127.0.0.1 at a free port (the daemon proxies it behind its token; the page has no run controls, since
anyone who may watch could press them), records the scene for replay, and runs the program on its
main thread, so a stop or the wall-clock limit reaches even a loop that never lets simulated time pass.

Its stdout is the daemon's event channel: one JSON object a line (`ready` with the viewer's port,
`output` text, `telemetry` of the robot's pose and wheel speeds every TELEMETRY_MS of simulated
time, `state` after a control, then `result`). Anything else that writes to stdout lands on stderr
instead. Its stdin takes controls, one JSON object a line: `{"cmd": "pause"|"resume"|"stop"}`,
`{"cmd": "speed", "speed": 2.0}` (null: as fast as possible). Stdin closing (the daemon went away)
stops the run.
"""

from __future__ import annotations

import json
import math
import os
import signal
import sys
import threading
import traceback
from dataclasses import replace

from .job import ERROR, SimJob, SimResult
from .limits import contain

TELEMETRY_MS = 100  # one pose and wheel-speed sample per this much simulated time

# `python -m openbricks_sim.console_job`, except that a stop while the simulator still imports ends
# the child quietly (as run_process.CHILD_MAIN does for `sim run`).
CHILD_MAIN = (
    "import sys\n"
    "try:\n"
    "    from openbricks_sim.console_job import main\n"
    "except KeyboardInterrupt:\n"
    "    sys.exit(130)\n"
    "sys.exit(main(sys.argv[1:]))\n"
)


class EventChannel:
    """JSON lines to the daemon, from any thread (the program's, viser's, the control reader's)."""

    def __init__(self, stream):
        self._stream = stream
        self._lock = threading.Lock()

    def send(self, type_: str, **data) -> None:
        line = json.dumps({"type": type_, **data}, separators=(",", ":"), allow_nan=False)
        with self._lock:
            try:
                self._stream.write(line + "\n")
                self._stream.flush()
            except (BrokenPipeError, ValueError):  # the daemon is gone: the stdin reader stops the run
                pass


def _event_channel() -> EventChannel:
    """Keep the real stdout for events and point fd 1 at stderr, so no stray print can garble them."""
    sys.stdout.flush()
    events_fd = os.dup(1)
    os.dup2(2, 1)
    return EventChannel(os.fdopen(events_fd, "w", encoding="utf-8", buffering=1))


def _wheel_sampler(simulation, events: EventChannel):
    """A clock callback sending the robot's pose and wheel speeds (deg/s, forward positive)."""
    physics = simulation.physics
    dofs = [joint.dofadr[0] for joint in physics.wheel_joints]

    def sample():
        pose = physics.pose()
        speeds = [math.degrees(physics.data.qvel[dof]) for dof in dofs]
        events.send(
            "telemetry",
            sim_ms=simulation.clock.now_ms(),
            x_mm=round(pose.x_mm, 2),
            y_mm=round(pose.y_mm, 2),
            heading_deg=round(pose.heading_deg, 2),
            left_dps=round(speeds[0], 1),
            right_dps=round(speeds[1], 1),
        )

    return sample


OUTPUT_CHUNK_MAX = 64 * 1024  # one print's text, at most, per output event


def _read_controls(viewer, events: EventChannel, gone: threading.Event) -> None:
    """Apply the daemon's controls until stdin closes; closing it stops the run."""
    for line in sys.stdin:
        try:
            command = json.loads(line)
            name = command["cmd"]
        except (ValueError, KeyError, TypeError):
            continue
        if name == "pause":
            viewer.paused = True
        elif name == "resume":
            viewer.paused = False
        elif name == "speed":
            viewer.speed = command.get("speed")
        elif name == "stop":
            viewer.request_stop()
            continue
        events.send("state", paused=viewer.paused, speed=viewer.speed)
    gone.set()
    viewer.request_stop()


def run_watched(job: SimJob, recording: str, events: EventChannel, plot_tag: str | None = None) -> SimResult:
    """Run `job` with its 3D view served and recorded, reporting to `events` as it goes."""
    from .run import with_source
    from .run_flash import prepare_hub_dir
    from .viewer import SimViewer
    from .viewer.session import watched_run

    job, source = with_source(job)
    job = replace(job, hub_dir=prepare_hub_dir(job.hub_dir))
    with SimViewer(port=0, speed=job.speed, controls=False, record=True) as viewer:
        gone = threading.Event()
        threading.Thread(
            target=_read_controls, args=(viewer, events, gone), name="controls", daemon=True
        ).start()

        def echo(text):
            viewer.write(text)
            events.send("output", text=text[:OUTPUT_CHUNK_MAX])

        def attached(simulation):
            simulation.clock.schedule(
                _wheel_sampler(simulation, events), TELEMETRY_MS * 1000, TELEMETRY_MS * 1000
            )
            # Ready once attached: a pause or a speed sent from now on applies to this run.
            events.send("ready", port=viewer.port, chassis=job.chassis)
            if gone.is_set():  # the daemon went away while the world was being built
                viewer.request_stop()

        result = watched_run(viewer, job, source, echo, on_attached=attached, plot_tag=plot_tag)
        with open(recording, "wb") as f:
            f.write(viewer.recording())
    return result


def main(argv=None) -> int:
    argv = sys.argv[1:] if argv is None else argv
    with open(argv[0], encoding="utf-8") as f:
        spec = json.load(f)
    job = SimJob.from_dict(spec["job"])
    events = _event_channel()
    contain(memory_mb=job.memory_mb, cpu_s=job.cpu_limit(watched=True))
    # The wall-clock watchdog and a stop reach the program as KeyboardInterrupt, even when this
    # process was started with SIGINT ignored.
    signal.signal(signal.SIGINT, signal.default_int_handler)
    try:
        result = run_watched(job, spec["recording"], events, spec.get("plot_tag"))
    except Exception as exc:  # noqa: BLE001 - the simulator could not start: that is the run's result
        text = "".join(traceback.format_exception_only(type(exc), exc)).strip()
        traceback.print_exc()
        result = SimResult(exit=ERROR, sim_ms=0, wall_s=0.0, pose={}, output="", error=text)
    signal.signal(signal.SIGXCPU, signal.SIG_IGN)  # the result is out: only the hard limit remains
    events.send("result", result=json.loads(result.to_json()))
    return 0


if __name__ == "__main__":
    sys.exit(main())
