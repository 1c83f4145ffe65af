"""The simulated robot behind a virtual hub: one world for the hub's uptime, and how hub time passes.

- `HubWorld` builds the Simulation (world, chassis), installs the simulator's MicroPython modules
  for this process, and holds the hub's side of the world: the program button the host presses,
  the robot put back on its start pose at every program run (props too; the wheels keep their
  angles, as a robot picked up and set down keeps its encoder counts), and the timers the hub's
  Python set, which a soft reset cancels as MicroPython's does.
- How hub time takes wall time is the simulation's Pacer (pacing.py), set up by the hub;
  `checked_time` is the hub code's `time`, whose sleeps check the run limits as they go.
- `RunLimits` bounds each program run in simulated and in wall-clock time.
"""

import threading
import types

import mujoco

from ..shim import Shim, mptime
from ..shim import micropython as shim_micropython
from ..simulation import Simulation

CHECK_SLICE_US = 20_000  # a long sleep checks the run limits (and a shutdown) this often
PROGRAM_BUTTON_PIN = 39
CLICK_HOLD_MS = 200  # the launcher debounces over two 50 ms polls; a click holds well past that


class RunLimitExceeded(BaseException):
    """A program run passed the virtual hub's time limit (a BaseException: `except Exception` in the
    program cannot keep it alive)."""

    message = "the run passed the virtual hub's time limit"

    def __str__(self):
        return self.args[0] if self.args else self.message


class ProgramButton:
    """GPIO 39 as the host presses it (control API), read by the launcher's poll on the sim clock.

    A click holds the button for CLICK_HOLD_MS of simulated time from the moment the hub first sees
    it, then leaves it up as long, so queued clicks read as separate presses.
    """

    def __init__(self, clock):
        self._clock = clock
        self._lock = threading.Lock()
        self._held = False
        self._clicks = 0
        self._click_started_us = None
        self._quiet_until_us = None

    def press(self):
        self._held = True

    def release(self):
        self._held = False

    def click(self):
        with self._lock:
            self._clicks += 1

    @property
    def pending_clicks(self):
        return self._clicks + (1 if self._click_started_us is not None else 0)

    def level(self):
        """What the pin reads now: 0 while pressed (the button pulls the line low)."""
        now = self._clock.now_us()
        hold_us = CLICK_HOLD_MS * 1000
        if self._click_started_us is not None and now - self._click_started_us >= hold_us:
            self._click_started_us = None
            self._quiet_until_us = now + hold_us
        if self._click_started_us is None and self._clicks:
            if self._quiet_until_us is None or now >= self._quiet_until_us:
                with self._lock:
                    self._clicks -= 1
                self._click_started_us = now
        return 0 if self._held or self._click_started_us is not None else 1


class _TimerTrackingClock:
    """The board's view of the clock: records the timers hub code schedules, so a soft reset can
    cancel them (MicroPython deinitialises every machine.Timer on soft reset)."""

    def __init__(self, clock):
        self._clock = clock
        self._handles = []

    def schedule(self, callback, delay_us, period_us=0):
        handle = self._clock.schedule(callback, delay_us, period_us)
        self._handles = [h for h in self._handles if not h.cancelled]
        self._handles.append(handle)
        return handle

    def cancel_all(self):
        for handle in self._handles:
            handle.cancel()
        self._handles = []

    def __getattr__(self, name):
        return getattr(self._clock, name)


class HubWorld:
    """One simulated robot in one world for the whole uptime of a virtual hub."""

    def __init__(self, world="empty", chassis="st3032", seed=0, nvs=None, epoch_ms=None):
        self.simulation = Simulation(world, chassis, seed, epoch_ms=epoch_ms, nvs=nvs)
        self.clock = self.simulation.clock
        self.board = self.simulation.board
        self._timers = _TimerTrackingClock(self.clock)
        self.board.clock = self._timers
        self.button = ProgramButton(self.clock)
        self.board.set_input(PROGRAM_BUTTON_PIN, self.button.level)
        physics = self.simulation.physics
        self._data = physics.data
        self._model = physics.model
        self._start_qpos = physics.data.qpos.copy()
        self._start_qvel = physics.data.qvel.copy()
        self._keep_qpos = [joint.qposadr[0] for joint in physics.wheel_joints]
        self._keep_qvel = [joint.dofadr[0] for joint in physics.wheel_joints]
        self._shim = None

    def install(self):
        """Make this process's `machine`, `time`, `esp32`, ... the simulated hub's (once)."""
        self._shim = Shim(self.simulation).install()
        shim_micropython.bind(self._timers)  # micropython.schedule() goes through the tracker too

    def close(self):
        if self._shim is not None:
            self._shim.uninstall()
            self._shim = None
        self.simulation.close()

    def cancel_timers(self):
        self._timers.cancel_all()

    def wall_time_passed(self, seconds):
        """`seconds` of wall time went by that simulated time did not follow (the hub sat at its
        prompt running no code, or the CPU could not keep up). The RTC is the hub's wall clock and
        keeps going, as a hub's does: without this every such moment would set it back against the
        host's clock, and the times stamped on run logs and printed by programs would drift."""
        if seconds > 0:
            self.clock.set_epoch_ms(self.clock.epoch_us() // 1000 + int(seconds * 1000))

    def reset_to_start(self):
        """Put the robot (and every prop) back where the world starts, at rest; time goes on."""
        data = self._data
        wheels_q = [data.qpos[i] for i in self._keep_qpos]
        data.qpos[:] = self._start_qpos
        data.qvel[:] = self._start_qvel
        for i, angle in zip(self._keep_qpos, wheels_q, strict=True):
            data.qpos[i] = angle
        for i in self._keep_qvel:
            data.qvel[i] = 0.0
        mujoco.mj_forward(self._model, data)

    def pose(self):
        pose = self.simulation.physics.pose()
        return {"x_mm": pose.x_mm, "y_mm": pose.y_mm, "heading_deg": pose.heading_deg}


def checked_time(check):
    """MicroPython's `time` for hub code: the simulator's, with sleeps that call check() every
    CHECK_SLICE_US of simulated time, so a run limit or a shutdown ends a sleeping program where a
    hub program expects to be stopped (in a sleep), not inside the runtime's own bookkeeping."""

    def sleep_us(us):
        remaining = int(us)
        while remaining > 0:
            chunk = min(remaining, CHECK_SLICE_US)
            mptime.sleep_us(chunk)
            remaining -= chunk
            check()

    module = types.ModuleType("time", mptime.__doc__)
    for name in dir(mptime):
        if not name.startswith("_") and name != "bind" and callable(getattr(mptime, name)):
            setattr(module, name, getattr(mptime, name))
    module.sleep_us = sleep_us
    module.sleep_ms = lambda ms: sleep_us(int(ms * 1000)) if ms > 0 else None
    module.sleep = lambda seconds: sleep_us(int(seconds * 1_000_000)) if seconds > 0 else None
    module.__getattr__ = mptime.__getattr__
    return module


class RunLimits:
    """Simulated- and wall-time limits of one program run (None: no limit)."""

    def __init__(self, clock, interrupt, sim_limit_ms=None, wall_limit_s=None):
        self._clock = clock
        self._interrupt = interrupt  # interrupt(exc_type): raise it in the running hub code
        self.sim_limit_ms = sim_limit_ms
        self.wall_limit_s = wall_limit_s
        self._started_us = None
        self._watchdog = None
        self._wall_error = type(
            "RunLimitExceeded",
            (RunLimitExceeded,),
            {"message": f"the run passed the virtual hub's wall-clock limit of {wall_limit_s:g} s"}
            if wall_limit_s is not None
            else {},
        )

    def start(self):
        self._started_us = self._clock.now_us()
        if self.wall_limit_s is not None:
            self._arm(self.wall_limit_s)

    def _arm(self, delay_s):
        self._watchdog = threading.Timer(delay_s, self._wall_expired)
        self._watchdog.daemon = True
        self._watchdog.start()

    def _wall_expired(self):
        if self._started_us is None:
            return
        self._interrupt(self._wall_error)
        self._arm(1.0)  # again, until the run is really over (a program may catch BaseException)

    def stop(self):
        self._started_us = None
        if self._watchdog is not None:
            self._watchdog.cancel()
            self._watchdog = None

    def check(self):
        """Raise RunLimitExceeded once the run has used up its simulated time."""
        if self._started_us is None or self.sim_limit_ms is None:
            return
        if self._clock.now_us() - self._started_us > self.sim_limit_ms * 1000:
            raise RunLimitExceeded(
                f"the run passed the virtual hub's limit of {self.sim_limit_ms} ms of simulated time"
            )
