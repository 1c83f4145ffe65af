"""One virtual hub: a byte stream in, MicroPython's REPL out, the simulator behind it.

Threads: a reader thread takes bytes from the link and runs them through the REPL protocol (which
answers prompts, echo and raw-paste flow control at once); code runs on the main thread, as on the
hub, where the protocol's Execute and SoftReboot requests are queued. A Ctrl-C from the link reaches
running code through the interrupt gate. The control socket (control.py) presses the program
button and reports status from a thread of its own.

A reset (power-up, machine.reset()) or soft reset gives the hub fresh Python state: the runtime and
the flash's modules are imported afresh, timers and controllers are stopped, the REPL namespace is
emptied; then the frozen boot.py runs, and in the friendly REPL main.py, which hands the hub to the
launcher until a host interrupts it. The simulated world persists for the process's lifetime
(flash and NVS persist across processes); each program run puts the robot back on its start pose.
"""

import fcntl
import importlib
import os
import queue
import sys
import threading
import time
from dataclasses import dataclass

from ..program_robot import ProgramRobot
from ..python_cost import PythonCost
from ..shim import micropython as shim_micropython
from . import frozen
from .console import ConsoleIn, ConsoleOut, make_input
from .endpoint import LOCK_FILE
from .gate import InterruptGate
from .hub_fs import DEFAULT_CAPACITY_BYTES, HubFS
from .hub_python import HubPython
from .nvs_store import PersistentNVS
from .repl import DEFAULT_PASTE_WINDOW, FRIENDLY, SOFT_REBOOT, Execute, Interrupt, ReplProtocol, SoftReboot
from .world import HubWorld, RunLimits, checked_time

MACHINE = "openbricks virtual hub (simulated) with ESP32S3"
EPOCH_2000_MS = 946684800000  # the RTC of a hub nobody has set yet reads 2000-01-01
NVS_NAMESPACE = "openbricks"
NVS_KEY_HUB_NAME = "hub_name"
NVS_KEY_BLE_ENABLED = "ble_enabled"
FLASH_DIR = "flash"
NVS_FILE = "nvs.json"


_END_OF_LINK = object()  # queued by the reader when the link ends
# After its host goes away, a hub switches off once no program has run for this long (the run log's
# closing lines are written just after a run ends).
_IDLE_BEFORE_POWER_OFF_S = 1.0


class HubShutdown(BaseException):
    """The virtual hub process is stopping: ends whatever hub code runs (a run is logged as such)."""

    def __str__(self):
        return "the virtual hub is shutting down"


class HubBusyError(RuntimeError):
    pass


@dataclass
class HubConfig:
    name: str
    directory: str  # the hub's own directory: flash/, nvs.json, control.sock
    world: str = "empty"
    chassis: str = "st3032"
    seed: int = 0
    speed: float | None = 1.0  # program runs: real-time factor, None = as fast as the CPU allows
    paste_window: int = DEFAULT_PASTE_WINDOW
    flash_bytes: int = DEFAULT_CAPACITY_BYTES
    run_sim_limit_ms: int | None = None
    run_wall_limit_s: float | None = None


class VirtualHub:
    """A virtual hub on `port` (read(n) -> bytes, b"" at the end; write(bytes); close())."""

    def __init__(self, config: HubConfig, port):
        self.config = config
        self.port = port
        os.makedirs(config.directory, exist_ok=True)
        self._lock_file = _lock_directory(config.directory)
        self._send_lock = threading.Lock()
        self._state_lock = threading.Lock()
        self._events = queue.Queue()
        self._closing = threading.Event()
        self.gate = InterruptGate()
        self._program_robot = None  # serve() installs it, after the hub's own import finder
        self.nvs = PersistentNVS(os.path.join(config.directory, NVS_FILE))
        self._name_hub(config.name)
        self.fs = HubFS(os.path.join(config.directory, FLASH_DIR), config.flash_bytes)
        self.world = HubWorld(config.world, config.chassis, config.seed, nvs=self.nvs, epoch_ms=EPOCH_2000_MS)
        self.protocol = ReplProtocol(self._send, paste_window=config.paste_window)
        self.stdout = ConsoleOut(self._send)
        self.stdin = ConsoleIn(self._take_stdin, self.gate.wakeup, peek=lambda: bool(self.protocol.stdin))
        self.gate.add_waiter(self.stdin.notify)
        self.limits = RunLimits(
            self.world.clock, self.gate.interrupt, config.run_sim_limit_ms, config.run_wall_limit_s
        )
        # Real time at the prompt and in the launcher's idle loop (an idle hub must not spin the
        # physics flat out), the hub's speed while a program runs (_on_run).
        self.pacer = self.world.simulation.pace(1.0, wakeup=self.gate.wakeup, on_behind=self._fell_behind)
        self.gate.add_waiter(self.pacer.nudge)
        self.python = HubPython(
            self.fs,
            checked_time(self._between_slices),
            MACHINE,
            input_fn=make_input(self.stdin, self.stdout),
            stdin_ready=self.stdin.wait_readable,
        )
        self.run_active = False
        self.runs_started = 0
        self._code_ended_at = None  # wall time the hub last went back to its prompt
        self._on_ready = None
        self._link_started = False
        self.control_path = None  # set by whoever serves the control socket

    # -- the link --------------------------------------------------------------------------------

    def _send(self, data):
        with self._send_lock:
            self.port.write(data)

    def _set_interrupt_char(self, char):
        """micropython.kbd_intr(char) of hub code: the byte the link turns into an interrupt."""
        with self._state_lock:
            self.protocol.interrupt_char = char if char >= 0 else -1

    def _take_stdin(self, n):
        with self._state_lock:
            return self.protocol.take_stdin(n)

    def _reader(self):
        while not self._closing.is_set():
            data = self.port.read(4096)
            if not data:
                break
            with self._state_lock:
                self._dispatch(self.protocol.feed(data))
            self.stdin.notify()
        # The host is gone for good (stdio closed): finish what it asked for, then stop.
        self._events.put(_END_OF_LINK)

    def _start_link(self):
        """The hub is up: listen to the link, and tell whoever waits for us (once)."""
        self._link_started = True
        threading.Thread(target=self._reader, name="virtual-hub-link", daemon=True).start()
        if self._on_ready is not None:
            ready, self._on_ready = self._on_ready, None
            ready()

    def _dispatch(self, events):
        """Route protocol events (call with the state lock held)."""
        for event in events:
            if isinstance(event, Interrupt):
                self.gate.interrupt()
            else:
                self._events.put(event)

    # -- serving ---------------------------------------------------------------------------------

    def serve(self, on_ready=None):
        """Run the hub on this (main) thread until the link closes or shutdown() is called.

        `on_ready()` is called once the hub is up (boot.py has run, main.py is about to), which is
        when a host should connect: a hub is up long before anyone plugs in its cable.
        """
        self._on_ready = on_ready
        sys.stdout = sys.stderr = self.stdout
        sys.stdin = self.stdin
        self.world.install()
        shim_micropython.bind_kbd_intr(self._set_interrupt_char)
        self.python.install()
        self._program_robot = ProgramRobot(self.world.simulation).install()  # after the hub's finder
        try:
            self._reset(hard=True)
            while not self._closing.is_set():
                try:
                    event = self._events.get(timeout=0.25)
                except queue.Empty:
                    continue
                if event is _END_OF_LINK:
                    if self._events.empty():
                        break
                    self._events.put(event)  # code the last bytes asked for is still queued
                    continue
                if isinstance(event, Execute):
                    self._execute(event)
                elif isinstance(event, SoftReboot):
                    self._send(SOFT_REBOOT)
                    self._reset(hard=False)
        except HubShutdown:
            pass
        finally:
            self.close()

    def shutdown(self):
        """Stop the hub (any thread): running hub code ends with HubShutdown, serve() returns."""
        if self._closing.is_set():
            return
        self._closing.set()
        self.gate.interrupt(HubShutdown)

    def power_off_when_idle(self):
        """The host that started this hub is gone (any thread): let the program that is running
        finish and log its end, as a hub left on the table would, then switch off, so no orphaned
        process stays behind."""

        def wait_then_shut_down():
            quiet_since = None
            while not self._closing.is_set():
                if self.run_active:
                    quiet_since = None
                elif quiet_since is None:
                    quiet_since = time.monotonic()
                elif time.monotonic() - quiet_since >= _IDLE_BEFORE_POWER_OFF_S:
                    break
                time.sleep(0.05)
            self.shutdown()

        threading.Thread(target=wait_then_shut_down, name="power-off", daemon=True).start()

    def close(self):
        self._closing.set()
        if self._program_robot is not None:
            self._program_robot.uninstall()
        self.python.uninstall()
        self.world.close()
        self.port.close()
        sys.stdout, sys.stderr, sys.stdin = sys.__stdout__, sys.__stderr__, sys.__stdin__

    # -- running code ------------------------------------------------------------------------------

    def _run(self, code):
        """Run compiled hub code behind the interrupt gate; returns the exception it ended with."""
        if self._code_ended_at is not None:
            self.world.wall_time_passed(time.monotonic() - self._code_ended_at)
            self.pacer.nudge()  # counted here: pacing must not count the wait at the prompt again
        outcome = None
        cost = PythonCost(self.world.clock)  # spinning code lets time pass, as on a hub
        try:
            try:
                self.gate.open()
                with cost:
                    self.python.run(code)
            except BaseException as exc:  # whatever hub code raised is its result
                outcome = exc
            finally:
                self.gate.close()
                cost.uninstall()  # again: an interrupt that landed in the with's exit skipped it
        except BaseException as late:  # an interrupt that landed as the code ended
            outcome = outcome or late
        self._code_ended_at = time.monotonic()
        if isinstance(outcome, HubShutdown) or self._closing.is_set():
            raise HubShutdown
        return outcome

    def _error_text(self, outcome):
        """The traceback the host sees, or None; a hard reset request is handled by the caller."""
        if outcome is None or isinstance(outcome, SystemExit):
            return None
        return self.python.traceback.format(outcome)

    def _finish(self, error_text):
        with self._state_lock:
            self.gate.discard_pending()
            self._dispatch(self.protocol.execution_done(error_text))
        self.stdin.notify()

    def _execute(self, event):
        mode = "single" if event.kind == FRIENDLY else "exec"
        try:
            code = self.python.compile(event.source, "<stdin>", mode)
        except (SyntaxError, ValueError, OverflowError) as exc:
            self._finish(self.python.traceback.format(exc))
            return
        outcome = self._run(code)
        if self._reset_requested(outcome):
            self._reset(hard=True)
            return
        self._finish(self._error_text(outcome))

    def _reset_requested(self, outcome):
        board = self.world.board
        if isinstance(outcome, SystemExit) and board.reset_requested:
            board.reset_requested = False
            return True
        return False

    # -- resets ------------------------------------------------------------------------------------

    def _reset(self, hard):
        """Fresh Python state, then the frozen boot.py (and main.py in the friendly REPL)."""
        if hard:
            with self._state_lock:
                self.protocol.start_boot()
        self._fresh_python()
        outcome = self._run(self.python.compile(frozen.BOOT_PY, "boot.py"))
        if self._reset_requested(outcome):
            return self._reset(hard=True)
        error = self._error_text(outcome)
        if error:
            self.stdout.write(error)  # printed as it happens; main.py still runs, as on the hub
        if not self._link_started:
            self._start_link()
        error = None
        if not self.protocol.raw_mode:
            outcome = self._run(self.python.compile(frozen.MAIN_PY, "main.py"))
            if self._reset_requested(outcome):
                return self._reset(hard=True)
            error = self._error_text(outcome)
        self._finish(error)
        return None

    def _fresh_python(self):
        self.world.cancel_timers()
        _stop_native_controllers()
        self.python.forget_modules()
        self.python.reset()
        self._set_run_active(False)
        self.limits.stop()
        launcher = importlib.import_module("openbricks.launcher")
        launcher.add_listener(self._on_run)
        runtime = importlib.import_module("openbricks")
        self.protocol.banner = (
            f"openbricks {runtime.firmware_label()} on virtual hub {self.config.name}; {MACHINE}\r\n"
            'Type "help()" for more information.\r\n'
        ).encode()

    def _on_run(self, running):
        """The launcher's start/end of a program run (main thread)."""
        if running:
            self.runs_started += 1
            self.world.reset_to_start()
            self.limits.start()
        else:
            self.limits.stop()
        self._set_run_active(running)

    def _set_run_active(self, running):
        self.run_active = running
        self.pacer.speed = self.config.speed if running else 1.0

    def _fell_behind(self, seconds):
        """The CPU could not keep the simulation up with real time (a loaded machine): at real-time
        speed the RTC still keeps real time, as a hub's own clock would."""
        if self.pacer.speed == 1.0:
            self.world.wall_time_passed(seconds)

    def _between_slices(self):
        if self._closing.is_set():
            raise HubShutdown
        self.limits.check()

    # -- NVS ---------------------------------------------------------------------------------------

    def _name_hub(self, name):
        """Write the hub's name (as `openbricks flash --name` does) and, on a new hub, BLE off: a
        virtual hub's link is its pty, it has no radio to bridge the REPL over."""
        items = dict(self.nvs.get(NVS_NAMESPACE, {}))
        changed = items.get(NVS_KEY_HUB_NAME) != name.encode()
        items[NVS_KEY_HUB_NAME] = name.encode()
        if NVS_KEY_BLE_ENABLED not in items:
            items[NVS_KEY_BLE_ENABLED] = 0
            changed = True
        if changed:
            self.nvs[NVS_NAMESPACE] = items

    # -- control API (any thread) ------------------------------------------------------------------

    def status(self):
        with self._state_lock:
            protocol = {
                "raw_repl": self.protocol.raw_mode,
                "executing": self.protocol.running is not None,
                "paste_window": self.protocol.paste_window,
                "paste_overrun_bytes": self.protocol.overrun_bytes,
            }
        return {
            "name": self.config.name,
            "pty": getattr(self.port, "path", None),
            "control": self.control_path,
            "directory": self.config.directory,
            "world": self.config.world,
            "chassis": self.config.chassis,
            "running": self.run_active,
            "runs_started": self.runs_started,
            "sim_ms": self.world.clock.now_ms(),
            "pose": self.world.pose(),
            "button_clicks_pending": self.world.button.pending_clicks,
            **protocol,
        }


def _stop_native_controllers():
    import openbricks_native

    openbricks_native.motor_process.reset()


def _lock_directory(directory):
    """Hold `directory` for this process: two hubs on one flash would corrupt each other."""
    path = os.path.join(directory, LOCK_FILE)
    handle = open(path, "a+")  # held for the process's lifetime
    try:
        fcntl.flock(handle, fcntl.LOCK_EX | fcntl.LOCK_NB)
    except BlockingIOError:
        handle.close()
        raise HubBusyError(
            f"another virtual hub is already running on {directory}: stop it, or give this one "
            "another --name or --dir"
        ) from None
    handle.seek(0)
    handle.truncate()
    handle.write(f"{os.getpid()}\n")
    handle.flush()
    return handle
