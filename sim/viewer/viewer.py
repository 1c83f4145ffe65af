"""SimViewer: a running Simulation mirrored into a viser server, for any number of browsers.

    viewer = SimViewer(port=8080)            # serves http://127.0.0.1:8080
    viewer.attach(simulation, stop=run.request_stop)
    run.run(source, echo=viewer.write)       # the program runs on this thread, paced by the viewer
    viewer.detach(result)
    viewer.close()

Three threads meet here. The simulation's thread (the one running the program) captures a Frame
each time the Pacer fires and is held back by it; viser's threads deliver button presses; a task on
viser's own event loop draws the newest Frame at up to `frame_hz` and redraws the status and output
panels a few times a second. Only the simulation's thread touches the live MuJoCo data. Drawing
happens on viser's loop, not on a thread of ours, because viser's outgoing buffer wakes its sender
through an asyncio.Event that is only safe to set from that loop: pushed from another thread, pose
updates sat unsent until something else woke the sender, and the page saw 15 poses a second
instead of 60.

The CLI uses it through serve_run(); the console's daemon holds one per sim job (a child process)
and proxies its page to the browsers that watch that job. With record=True every run is also kept
as a viser scene recording (`recording()`, a `.viser` file's bytes) timed by simulated time, so the
run can be played back later at its own pace whatever speed it was watched at.
"""

from __future__ import annotations

import _thread
import asyncio
import concurrent.futures
import contextlib
import io
import ipaddress
import logging
import threading
import time
from collections import deque

import viser

from ..chassis import ROBOT_BODY
from ..pacing import DEFAULT_FRAME_HZ
from .frames import capture
from .output import OutputTail
from .panel import ControlPanel
from .scene import SceneMirror, model_fingerprint

DEFAULT_HOST = "127.0.0.1"
DEFAULT_PORT = 8080
# Status and output text change often but are read by people: a few redraws a second are plenty.
_TEXT_REFRESH_S = 0.2
# The real-time factor shown is measured over this much wall-clock time.
_RATE_WINDOW_S = 1.0
# A Stop press that the program has not noticed after this long (a loop that never lets simulated
# time pass) is delivered as a KeyboardInterrupt to the thread running it, as Ctrl-C would be.
_STOP_ESCALATION_S = 1.0

_log = logging.getLogger(__name__)

WAITING = "waiting"
RUNNING = "running"
PAUSED = "paused"


class RemoteBindError(ValueError):
    """The viewer was asked to listen beyond this machine without saying that is intended."""


class SimViewer:
    """A viser server showing one simulation at a time, with run controls and the program's output.

    host/port: where to listen (127.0.0.1 by default; if the port is taken viser moves to the next
    free one: read `url`/`port`). speed: the real-time factor runs start at (None: as fast as
    possible). controls=False shows the run without letting the page steer it. viser has no
    authentication, so any host other than a loopback address needs allow_remote=True: sharing a
    run beyond this machine is the console's business, behind its token.
    """

    def __init__(
        self,
        host: str = DEFAULT_HOST,
        port: int = DEFAULT_PORT,
        *,
        speed: float | None = 1.0,
        controls: bool = True,
        frame_hz: float = DEFAULT_FRAME_HZ,
        allow_remote: bool = False,
        title: str = "openbricks sim",
        record: bool = False,
    ):
        if not allow_remote and not _is_loopback(host):
            raise RemoteBindError(
                f"the 3D viewer would listen on {host}, reachable from other machines, and it has no "
                "login: keep the default 127.0.0.1, or let a remote mentor watch through the console"
            )
        self._frame_hz = float(frame_hz)
        self._speed = speed
        self._paused = False
        self._lock = threading.RLock()
        self._simulation = None
        self._pacer = None
        self._stop_run = None
        self._run_thread = None
        self._state = WAITING
        self._frame = None
        self._mirror = None
        self._fingerprint = None
        self._scene_lock = threading.Lock()  # the scene is rebuilt on one thread and drawn on another
        self._rates = deque()  # (wall_s, sim_ms) of recent frames; the publishing task's alone
        self._rate_epoch = 0  # bumped when the measured rate must start over (new run, new speed)
        self._record = record
        self._recorder = None  # viser's scene serializer while a run is recorded
        self._recorded_ms = 0  # simulated time of the last frame in the recording
        self.output = OutputTail()
        self.restart_requested = threading.Event()
        self.stop_requested = threading.Event()
        # viser prints a banner (and a goodbye) on stdout; the program's output goes there too.
        with contextlib.redirect_stdout(io.StringIO()):
            self.server = viser.ViserServer(host=host, port=port, label=title, verbose=False)
        try:
            self.server.gui.configure_theme(show_share_button=False, control_width="medium")
            self.panel = ControlPanel(
                self.server.gui,
                speed=speed,
                controls=controls,
                on_pause=self._on_pause,
                on_speed=self._on_speed,
                on_restart=self.request_restart,
                on_stop=self.request_stop,
                on_view=self._on_view,
            )
            self._visualization = self.server.gui.add_folder("Visualization", expand_by_default=False)
            self._closing = threading.Event()
            self._publisher = asyncio.run_coroutine_threadsafe(
                self._publish_loop(), self.server.get_event_loop()
            )
        except BaseException:
            self._stop_server()
            raise

    # --- where to look ----------------------------------------------------------------------------

    @property
    def port(self) -> int:
        return self.server.get_port()

    @property
    def url(self) -> str:
        host = self.server.get_host()
        if ":" in host:
            host = f"[{host}]"
        return f"http://{host}:{self.port}"

    # --- one run ----------------------------------------------------------------------------------

    def attach(self, simulation, stop=None) -> None:
        """Show `simulation` and pace it; call from the thread that will run its program.

        stop() is how the page's Stop and Restart buttons end the run (a ProgramRun's
        request_stop). A simulation built with a speed hands that speed to the viewer, which paces
        from now on.
        """
        with self._lock:
            if self._simulation is not None:
                raise RuntimeError("the viewer already shows a simulation: detach() it first")
            if simulation.pacer is not None:  # a simulation built with a speed hands it over
                self._speed = simulation.pacer.speed
                self.panel.set_speed(self._speed)
            self._ensure_scene(simulation.physics.model)
            self._simulation = simulation
            self._stop_run = stop
            self._run_thread = threading.current_thread()
            self.restart_requested.clear()
            self.stop_requested.clear()
            self._rate_epoch += 1
            self._paused = False
            self.panel.set_paused(False)
            self._frame = capture(simulation)
            if self._record:
                self._start_recording()
            self._state = RUNNING
            self._pacer = simulation.pace(self._speed, on_frame=self._on_pacer_frame, frame_hz=self._frame_hz)

    def show_still(self, simulation, state: str) -> None:
        """Show `simulation` as it is now, with no run attached (a preview of a world)."""
        with self._lock:
            if self._simulation is not None:
                raise RuntimeError("the viewer is showing a run: detach() it first")
            self._ensure_scene(simulation.physics.model)
            self._frame = capture(simulation)
            self._state = state

    def detach(self, result=None) -> None:
        """The run is over: show where it ended and how (`result`: its RunResult)."""
        with self._lock:
            simulation = self._simulation
            if simulation is None:
                return
            self._pacer.stop()
            self._pacer = None
            self._frame = capture(simulation)
            self._simulation = None
            self._stop_run = None
            self._run_thread = None
            self._state = result.exit if result is not None else "ended"
            if result is not None and result.error:
                self.output.write(("\n" if self.output.lines() else "") + result.error)

    def recording(self, timeout_s: float = 10.0) -> bytes:
        """The last run as a `.viser` recording (record=True): the scene as it was when the run began,
        then every frame drawn, ending on the frame the run ended with. Call after detach()."""
        if self._recorder is None:
            raise RuntimeError("nothing was recorded: build the viewer with record=True and attach a run")
        future = asyncio.run_coroutine_threadsafe(self._end_recording(), self.server.get_event_loop())
        return future.result(timeout_s)

    def write(self, text: str) -> int:
        """Program output for the Output panel (pass as the run's echo)."""
        return self.output.write(text)

    @property
    def speed(self) -> float | None:
        return self._speed

    @speed.setter
    def speed(self, value: float | None) -> None:
        self._on_speed(value)

    @property
    def paused(self) -> bool:
        return self._paused

    @paused.setter
    def paused(self, value: bool) -> None:
        self.panel.set_paused(bool(value))
        self._on_pause(bool(value))

    @property
    def state(self) -> str:
        """waiting (nothing attached yet), running, paused, or how the last run ended."""
        return self._state

    def request_restart(self) -> None:
        """End the current run (if any) and ask the owner to start the program again."""
        self.restart_requested.set()
        self.request_stop()

    def request_stop(self) -> None:
        """End the current run; a program stuck in a loop that never lets time pass is interrupted."""
        with self._lock:
            if self._simulation is None:
                return
            self.stop_requested.set()
            if self._stop_run is not None:
                self._stop_run()
            self._pacer.stop()  # a paused run must wake up to notice it was stopped
            run_thread = self._run_thread
            simulation = self._simulation
        if run_thread is threading.main_thread():
            threading.Thread(
                target=self._escalate_stop, args=(simulation,), name="sim-viewer-stop", daemon=True
            ).start()

    def wait_for_restart(self, timeout_s: float | None = None) -> bool:
        """Block until the page asks for a restart (True) or timeout_s passes (False).

        Waits in short slices so Ctrl-C reaches a caller on the main thread promptly.
        """
        deadline = None if timeout_s is None else time.monotonic() + timeout_s
        while not self.restart_requested.is_set():
            if deadline is not None and time.monotonic() >= deadline:
                return False
            self.restart_requested.wait(0.2)
        return True

    def close(self) -> None:
        """Stop serving (idempotent). An attached run is released first."""
        with self._lock:
            if self._pacer is not None:
                self._pacer.stop()
        self._closing.set()
        concurrent.futures.wait([self._publisher], timeout=2.0)
        self._stop_server()

    def __enter__(self):
        return self

    def __exit__(self, *exc_info):
        self.close()

    # --- internals ----------------------------------------------------------------------------------

    def _ensure_scene(self, model) -> None:
        """Build the scene for `model`, unless the one on show already draws the same world."""
        fingerprint = model_fingerprint(model)
        if self._mirror is None or fingerprint != self._fingerprint:
            self._build_scene(model)
            self._fingerprint = fingerprint

    def _build_scene(self, model) -> None:
        with self._scene_lock:
            if self._mirror is not None:
                self._mirror = None
                self.server.scene.reset()
                self.server.scene.set_up_direction("+z")
                self._visualization.remove()
                self._visualization = self.server.gui.add_folder("Visualization", expand_by_default=False)
            mirror = SceneMirror(self.server, model, focus_body=ROBOT_BODY)
            with self._visualization:
                mirror.add_visualization_gui()
            mirror.reset_cameras()
            self._mirror = mirror

    def _start_recording(self) -> None:
        with self._scene_lock:
            if self._recorder is not None:  # an earlier run nobody asked for: let viser drop it
                self._recorder.serialize()
            self._recorder = self.server.get_scene_serializer()
            self._recorded_ms = self._frame.sim_ms
            self._mirror.show(self._frame)  # the first frame is in the recording at its start

    def _record_time(self, frame) -> None:
        """Advance the recording's clock to `frame` (called just before it is drawn)."""
        if self._recorder is not None and frame.sim_ms > self._recorded_ms:
            self._recorder.insert_sleep((frame.sim_ms - self._recorded_ms) / 1000.0)
            self._recorded_ms = frame.sim_ms

    async def _end_recording(self) -> bytes:
        # On viser's loop, like every other draw: the final frame goes in last, then the file is closed.
        with self._scene_lock:
            recorder, frame = self._recorder, self._frame
            if frame is not None and self._mirror is not None:
                self._record_time(frame)
                self._mirror.show(frame)
            self._recorder = None
        return recorder.serialize()

    def _on_pacer_frame(self) -> None:
        # On the simulation's thread, between physics steps.
        simulation = self._simulation
        if simulation is not None:
            self._frame = capture(simulation)

    def _on_pause(self, paused: bool) -> None:
        with self._lock:
            self._paused = paused
            if self._pacer is not None:
                self._pacer.paused = paused
                self._state = PAUSED if paused else RUNNING

    def _on_speed(self, speed: float | None) -> None:
        with self._lock:
            self._speed = speed
            if self._pacer is not None:
                self._pacer.speed = speed
            self._rate_epoch += 1

    def _on_view(self) -> None:
        if self._mirror is not None:
            self._mirror.reset_cameras()

    def _escalate_stop(self, simulation) -> None:
        deadline = time.monotonic() + _STOP_ESCALATION_S
        while time.monotonic() < deadline:
            if self._simulation is not simulation:
                return
            time.sleep(0.05)
        with self._lock:
            if self._simulation is simulation:
                _thread.interrupt_main()

    async def _publish_loop(self) -> None:
        period = 1.0 / self._frame_hz
        drawn = {"frame": None, "output": -1, "text_due": 0.0, "rate_epoch": -1}
        next_frame = time.perf_counter()
        failures = 0
        while not self._closing.is_set():
            try:
                self._publish(drawn)
                failures = 0
            except Exception:  # one bad frame must not freeze the view for the rest of the run
                failures += 1
                if failures == 1:
                    _log.exception("the 3D viewer could not draw a frame")
            next_frame = max(next_frame + period, time.perf_counter())
            await asyncio.sleep(max(0.0, next_frame - time.perf_counter()))

    def _publish(self, drawn: dict) -> None:
        """Draw what changed since the last call: the newest frame, then (a few times a second) text."""
        frame = self._frame
        if drawn["rate_epoch"] != self._rate_epoch:
            drawn["rate_epoch"] = self._rate_epoch
            self._rates.clear()
        # A scene being rebuilt on the simulation's thread is skipped, not waited for: this runs on
        # viser's loop, which must keep serving meanwhile.
        if frame is not None and frame is not drawn["frame"] and self._scene_lock.acquire(blocking=False):
            try:
                if self._mirror is not None:
                    self._record_time(frame)
                    self._mirror.show(frame)
            finally:
                self._scene_lock.release()
            drawn["frame"] = frame
            self._rates.append((frame.wall_s, frame.sim_ms))
        now = time.perf_counter()
        if now < drawn["text_due"]:
            return
        drawn["text_due"] = now + _TEXT_REFRESH_S
        if frame is not None:
            self.panel.show_status(self._state, frame.sim_ms, self._real_time_factor(now))
            self.panel.show_pose(frame.x_mm, frame.y_mm, frame.heading_deg)
        picture = None if frame is None else frame.display
        if picture is not None and picture.writes != drawn.get("display"):
            drawn["display"] = picture.writes
            self.panel.show_display(picture.block_text())
        version = self.output.version
        if version != drawn["output"]:
            drawn["output"] = version
            self.panel.show_output(self.output.lines())

    def _real_time_factor(self, now: float) -> float | None:
        if self._state != RUNNING:
            return None
        rates = self._rates
        while len(rates) > 2 and now - rates[0][0] > _RATE_WINDOW_S:
            rates.popleft()
        if len(rates) < 2:
            return None
        (wall0, sim0), (wall1, sim1) = rates[0], rates[-1]
        return (sim1 - sim0) / 1000.0 / (wall1 - wall0) if wall1 > wall0 else None

    def _stop_server(self) -> None:
        with contextlib.redirect_stdout(io.StringIO()):
            self.server.stop()


def _is_loopback(host: str) -> bool:
    if host == "localhost":
        return True
    try:
        return ipaddress.ip_address(host).is_loopback
    except ValueError:
        return False
