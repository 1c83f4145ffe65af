"""Program launcher: the program button starts and stops the staged program; every run is logged.

Button semantics (one GPIO, every press means start-or-stop):

- idle: a full press-release starts the program, on release, unless a stop happened less than
  START_LOCKOUT_MS ago (the bounce of the stopping press must not restart the robot); the starting
  press's own chatter is consumed (START_PRESS_OPEN_MS, RELEASE_CHATTER_MS);
- running: the stop fires on press-down. The e-stop latch engages first (motors halt, motion
  commands raise), then a KeyboardInterrupt is injected and re-injected every STOP_RETRY_MS until the
  program is actually dead: a user `try/except` may swallow one, and on the ESP32 a timer callback
  can only ask for the interrupt, not deliver it.

The watcher is a `machine.Timer` callback that lives for the whole uptime (never deinit'ed), so it
keeps running when a host session interrupts the idle loop. On the ESP32 that callback runs from the
MicroPython scheduler, between the main thread's bytecodes. That has two consequences for the design:

- the program itself always runs in the main thread, never inside the callback: a callback holds
  the scheduler lock, so a program started there would freeze every timer (the motor control tick,
  the log pump and this very stop button) for its whole run. The callback only sets a flag that the
  idle loop (`run()` / `Launcher.idle()`) picks up. While a host console session holds the main
  thread, a start press is refused with a console message instead; the host hands the hub back to
  the idle loop when it disconnects (`host_calls.idle()`).
- an exception raised in a scheduled callback is caught and printed by MicroPython, it never reaches
  the program. So the interrupt is requested through the firmware's native hook
  (`_openbricks_native.interrupt_main`, the same C path Ctrl-C takes) when the build has it. Without
  it the tick raises KeyboardInterrupt itself, which unwinds the program wherever timer callbacks run
  inline in the main thread (the simulator's virtual clock, the test fakes); on such a firmware the
  e-stop latch is what ends the program, at its next wait() or motion command.

Every run ends the same way, whatever ended it: the motors its drivers registered with the e-stop
are halted, drive bases give their serial-bus wheels back to the engine, servo buses close and the
native scheduler forgets the program's controllers, so the next run starts from a clean hub.

Log framing, one stamped line each, committed immediately:
`started: <trigger> | firmware <label> | program <path> | uptime N ms | free N B`,
`button pressed -> stop`, `estop engaged`, then one of `stopped: finished after N ms`,
`stopped: KeyboardInterrupt (N ms after press, M retries)`, `stopped: KeyboardInterrupt (Ctrl-C from
the console)`, or the full traceback followed by `stopped: <Exception>: <message> after N ms`.
"""

import gc
import io
import os
import sys
import time

import machine

import openbricks
from openbricks import _native, estop, log, pins, timers

DEFAULT_PROGRAM_PATH = "/program.mpy"
DEFAULT_BUTTON_PIN = 39
DEFAULT_POLL_MS = 50
DEFAULT_TIMER_ID = timers.LAUNCHER
_TIMER_ROLE = "launcher"

_running = [False]  # hub-wide "a program is running", read by the status LED on every tick
_listeners = []
_launcher = [None]


_last_end = [None]  # (run log index, outcome, trigger, stopped by) of the latest run


def program_running():
    """True while a user program is executing, whatever started it. One read, no allocation."""
    return _running[0]


def last_end():
    """How the latest run ended, or None: (run log index, outcome ("finished", "stopped", "error"),
    trigger ("host run", "button press"), stopped by ("console", "button" or None)). A new tuple
    per run, so a caller can tell whether it has seen this one."""
    return _last_end[0]


def add_listener(callback):
    """Call `callback(running)` on every program start (True) and end (False)."""
    if callback not in _listeners:
        _listeners.append(callback)


def remove_listener(callback):
    if callback in _listeners:
        _listeners.remove(callback)


def _set_running(running):
    if _running[0] == running:
        return
    _running[0] = running
    for callback in tuple(_listeners):
        try:
            callback(running)
        except Exception as exc:  # noqa: BLE001 - an LED listener must never break a run
            print("launcher: running listener failed: %r" % (exc,))


_EVENT_RING = 16
_events = []  # (ticks_ms, what) of the latest button decisions, oldest first


def _event(now, what):
    if len(_events) >= _EVENT_RING:
        _events.pop(0)
    _events.append((now, what))


def dump_events():
    """Print the latest program-button decisions, oldest first (why a press did or didn't act)."""
    for at_ms, what in _events:
        print("%10d ms  %s" % (at_ms, what))


def _acknowledge(stop):
    """Flash the status LED's press colour, if the BLE-button watcher that owns the LED is loaded."""
    button = sys.modules.get("openbricks.bluetooth_button")
    if button is not None:
        button.notify_press(stop)


def _raise_interrupt():
    raise KeyboardInterrupt


def _native_interrupt():
    """The firmware's C hook that raises KeyboardInterrupt in the main thread, or None."""
    return _native.get("interrupt_main")


def _native_wipe():
    """Drop the finished program's controllers from the native scheduler, if this build has one."""
    reset = getattr(_native.get("motor_process"), "reset", None)
    if reset is not None:
        reset()


def _release_program_hardware(halts):
    """Put the hardware a finished program drove back in the state the next program expects.

    Its motors are halted (a run that ended or failed mid-drive must not leave the robot moving),
    serial-bus wheels adopted by its drive bases go back to their engine, its servo buses close
    (UART and pins free, so the next program can wire the bus its own way and adopt the wheels
    again), and its controllers leave the native scheduler. Only modules the program imported are
    touched. Returns the lines worth a note in the run log; never raises.
    """
    notes = []
    for _halt, exc in estop.halt_since(halts):
        notes.append("a motor halt at the end of the run failed: " + _exception_line(exc))
    for name, action in (
        ("openbricks.robotics.wheels", "release_ports"),
        ("openbricks.drivers.st3215", "forget_buses"),
    ):
        module = sys.modules.get(name)
        if module is None:
            continue
        try:
            getattr(module, action)()
        except Exception as exc:  # noqa: BLE001 - the hub must keep serving the button
            notes.append("%s.%s() failed at the end of the run: %s" % (name, action, _exception_line(exc)))
    try:
        _native_wipe()
    except Exception as exc:  # noqa: BLE001
        notes.append("native scheduler reset failed: " + _exception_line(exc))
    return notes


def traceback_text(exc):
    """The traceback of what a program raised, with the program's own frames only.

    The runtime's frames (this launcher running the program, a driver the program called) say
    nothing the person can act on, and the error message names what went wrong; the program's
    frames show where. Works on MicroPython and on CPython (the simulator provides MicroPython's
    sys.print_exception there).
    """
    buf = io.StringIO()
    sys.print_exception(exc, buf)
    return user_frames(buf.getvalue())


def user_frames(text):
    """MicroPython traceback `text` without the lines of frames in the runtime's own files."""
    kept = []
    dropped = False  # the last frame was dropped: so is the source line CPython shows under it
    for line in text.split("\n"):
        if line.startswith('  File "'):
            name = line[8 : line.find('"', 8)]
            dropped = name.startswith("openbricks/") or "/openbricks/" in name
        elif not (dropped and line.startswith("    ")):
            dropped = False
        if not dropped:
            kept.append(line)
    return "\n".join(kept)


def _exception_line(exc):
    text = str(exc)
    return type(exc).__name__ + (": " + text if text else "")


def _advice(exc, free):
    """What to do, after a traceback whose last line says too little to act on."""
    if isinstance(exc, MemoryError):
        return (
            "the program ran out of memory (%s bytes were free when it started): build smaller lists and "
            "buffers, drop what you no longer need (del, gc.collect()), or work in smaller pieces\n" % free
        )
    return ""


def resolve_program(path=DEFAULT_PROGRAM_PATH):
    """The staged program to run: `path`, or its `.py`/`.mpy` sibling when only that one exists."""
    candidates = (path,)
    if path.endswith(".mpy"):
        candidates = (path, path[:-4] + ".py")
    elif path.endswith(".py"):
        candidates = (path, path[:-3] + ".mpy")
    for candidate in candidates:
        try:
            os.stat(candidate)
            return candidate
        except OSError:
            pass
    raise OSError(2, "no program staged at %s: upload one with `openbricks upload` or `run`" % path)


def _staged_name(path):
    """The program's own file name for a source staged as /program.py, which staging writes beside it
    as /program.name ("<size>\n<name>"), so a button run's traceback names the program as a host run's
    does. None when there is none, or it describes another file (its size differs)."""
    try:
        with open(path[:-3] + ".name") as f:
            size, name = f.read().split("\n", 1)
        return name if name and int(size) == os.stat(path)[6] else None
    except (OSError, ValueError):
        return None


def _forget_program_modules(before, directory):
    """Drop the modules the program loaded from the filesystem, so a re-uploaded helper loads fresh.

    Only files (relative paths are the hub's filesystem, absolute ones under the program's
    directory) are dropped: built-in modules, openbricks itself and, on CPython, the simulator's
    libraries stay loaded.
    """
    prefix = directory.rstrip("/") + "/"
    for name in tuple(sys.modules):
        if name in before or name.startswith("openbricks"):
            continue
        where = getattr(sys.modules[name], "__file__", None)
        if where and (not where.startswith("/") or where.startswith(prefix)):
            del sys.modules[name]


def _execute(path, name=None):
    """Run the program file in this thread with print teed into the run log.

    The program's directory leads sys.path for the run, so its helper modules import as they would
    next to a script on a computer.
    """
    cut = path.rfind("/")
    directory = path[:cut] if cut > 0 else "/"
    before = set(sys.modules)
    saved_print = None
    try:
        import builtins

        saved_print = builtins.print
        builtins.print = log.tee_print
    except (ImportError, AttributeError):
        saved_print = None  # a port without overridable builtins: the namespace injection below
    sys.path.insert(0, directory)
    try:
        if path.endswith(".py"):
            with open(path) as f:
                code = compile(f.read(), name or path, "exec")
            exec(code, {"__name__": "__main__", "__file__": path, "print": log.tee_print})
        else:
            # Bytecode (.mpy) can only be loaded through import, so it runs with __name__ "program".
            __import__(path[cut + 1 : path.rfind(".")])
    finally:
        sys.path.remove(directory)
        if saved_print is not None:
            import builtins

            builtins.print = saved_print
        _forget_program_modules(before, directory)


class Launcher:
    """The program-button watcher and the run wrapper; one per hub (see `get()`).

    `button` is the program button's GPIO number (claimed, input with pull-up), or a Pin-like object
    with value() (pressed reads 0) that the caller wired itself. The timing constants below are
    class attributes, so a hub with a bouncier button can subclass and change them.
    """

    #: A level must hold this many polls in a row to count as a press or a release.
    DEBOUNCE_TICKS = 2
    #: After a stop, presses are ignored this long, in ms (the stopping press bounces).
    START_LOCKOUT_MS = 500
    #: A press this soon after a start, in ms, is the starting press's chatter.
    RUN_START_GRACE_MS = 400
    #: The interrupt is requested again this often, in ms, until the program is dead.
    STOP_RETRY_MS = 300
    #: A gap this long between ticks, in ms, is worth a line in the run log.
    STARVE_NOTE_MS = 5000
    #: After the release that starts a program, further releases this soon (ms) are that press's
    #: chatter: they never queue a second start (a program that ends at once is not started again).
    START_PRESS_OPEN_MS = 600
    #: A press this soon after that release, in ms, is its chatter too, not a stop of the new run.
    RELEASE_CHATTER_MS = 500

    def __init__(
        self,
        button=DEFAULT_BUTTON_PIN,
        program_path=DEFAULT_PROGRAM_PATH,
        poll_ms=DEFAULT_POLL_MS,
        log_dir=log.LOG_DIR,
        interrupt=None,
    ):
        if isinstance(button, int):
            pins.claim(
                button,
                "program button",
                "pass button_pin= to launcher.run() to move the program button",
                owner="launcher",
                output=False,
            )
            # Input with pull-up, pressed = 0. The classic ESP32's GPIO 34-39 have no internal
            # pull-up: wire an external 10 kOhm one there.
            self._button = machine.Pin(button, machine.Pin.IN, machine.Pin.PULL_UP)
            self.button_pin = button
        elif callable(getattr(button, "value", None)):
            self._button = button
            self.button_pin = None  # the caller's pin: nothing claimed, nothing to release
        else:
            raise TypeError(
                "Launcher(button=%r): give the program button's GPIO number, or a Pin whose value() "
                "reads 0 while pressed" % (button,)
            )
        self.program_path = program_path
        self.poll_ms = poll_ms
        self.log_dir = log_dir
        self._interrupt = interrupt or _native_interrupt() or _raise_interrupt
        self._timer = None
        self._idling = False
        self._start_requested = False
        self._down = False  # debounced button level
        self._flips = 0  # consecutive polls that disagreed with the debounced level
        self._press_stops = False  # the press being held began as a stop (its release must not start)
        self._lockout_until_ms = None
        self._started_ms = None
        self._stop_pressed_ms = None  # when the stop press landed, for the stopped: line
        self._last_attempt_ms = None
        self._stop_retries = 0
        self._last_tick_ms = None
        self._start_released_ms = None  # the release that queued the last start
        self._halts_mark = None  # estop.mark() of the running program, until its hardware is released

    # -- the watcher (timer callback context) ------------------------------------------------

    def start_watcher(self, timer_id=DEFAULT_TIMER_ID):
        """Poll the button from a periodic hardware timer, for the rest of the uptime."""
        timers.claim(timer_id, _TIMER_ROLE, "pass timer_id= to launcher.start()")
        self._timer_id = timer_id
        self._timer = machine.Timer(timer_id)
        self._timer.init(mode=machine.Timer.PERIODIC, period=self.poll_ms, callback=self._on_timer)

    def _on_timer(self, _timer):
        self._tick()

    def _tick(self):
        """One poll: pump the log, debounce the button, act on edges, retry a pending stop.

        Runs in the scheduler: it must never raise, except the deliberate KeyboardInterrupt.
        """
        now = time.ticks_ms()
        interrupt = False
        try:
            if self._last_tick_ms is not None and _running[0]:
                gap = time.ticks_diff(now, self._last_tick_ms)
                if gap >= self.STARVE_NOTE_MS:
                    log.note(
                        "watcher tick starved for %d ms (slowest log write %d ms)"
                        % (gap, log.worst_write_ms())
                    )
            self._last_tick_ms = now
            log.pump()
            down = self._button.value() == 0
            if down == self._down:
                self._flips = 0
            else:
                self._flips += 1
                if self._flips >= self.DEBOUNCE_TICKS:
                    self._flips = 0
                    self._down = down
                    interrupt = self._on_press(now) if down else self._on_release(now)
            if not interrupt and _running[0] and self._stop_pressed_ms is not None:
                if time.ticks_diff(now, self._last_attempt_ms) >= self.STOP_RETRY_MS:
                    _event(now, "stop retry")
                    self._stop_retries += 1
                    self._last_attempt_ms = now
                    interrupt = True
        except Exception as exc:  # noqa: BLE001 - the stop button must survive any one bad tick
            print("launcher: watcher tick failed: %r" % (exc,))
        if interrupt:
            self._interrupt()

    def _since_start_release(self, now, window_ms):
        """True within `window_ms` of the release that queued the last start."""
        released = self._start_released_ms
        return released is not None and time.ticks_diff(now, released) < window_ms

    def _locked_out(self, now):
        return self._lockout_until_ms is not None and time.ticks_diff(self._lockout_until_ms, now) > 0

    def _on_press(self, now):
        """Debounced press-down; returns True when the program must be interrupted now."""
        self._press_stops = _running[0] or self._locked_out(now)
        if not _running[0]:
            _event(now, "press (idle%s)" % (", locked out" if self._press_stops else ""))
            return False
        if self._stop_pressed_ms is not None:
            _event(now, "press while stopping: ignored")
            return False
        if self._started_ms is not None and time.ticks_diff(now, self._started_ms) < self.RUN_START_GRACE_MS:
            _event(now, "press within the start grace: ignored")
            return False
        if self._since_start_release(now, self.RELEASE_CHATTER_MS):
            _event(now, "press within the start release's chatter: ignored")
            return False
        _event(now, "press -> stop")
        _acknowledge(True)
        self._stop_pressed_ms = now
        self._last_attempt_ms = now
        self._stop_retries = 0
        # Halting comes before the first commit: a littlefs commit takes 60-90 ms on the hub, and
        # the robot keeps driving meanwhile. The line is committed with "estop engaged" below.
        log.note("button pressed -> stop", commit=False)
        failures = estop.engage("program button")
        line = "estop engaged"
        for _halt, exc in failures:
            line += "; a motor halt failed: " + _exception_line(exc)
        log.note(line)
        return True

    def _on_release(self, now):
        """Debounced release: starts the program when the whole press happened while idle."""
        stopping_press = self._press_stops
        self._press_stops = False
        if stopping_press:
            # The contacts bounce as the stopping press lets go: keep starts shut a while longer.
            self._lockout_until_ms = time.ticks_add(now, self.START_LOCKOUT_MS)
            _event(now, "release of a stopping press")
            return False
        if _running[0] or self._locked_out(now):
            _event(now, "release: ignored (%s)" % ("running" if _running[0] else "locked out"))
            return False
        if self._since_start_release(now, self.START_PRESS_OPEN_MS):
            _event(now, "release: chatter of the start press, ignored")
            return False
        if self._idling:
            _event(now, "release -> start")
            _acknowledge(False)
            self._start_requested = True
            self._start_released_ms = now
        else:
            _event(now, "release: start refused, console session")
            print(
                "program button: start refused, a console session holds the hub; "
                "disconnect the host (or press reset) and press again"
            )
        return False

    def note_external_stop(self):
        """Arm the start lockout for a stop that did not come from this watcher (a console Ctrl-C),
        so the echoes of that stop can't read as a fresh start press."""
        self._lockout_until_ms = time.ticks_add(time.ticks_ms(), self.START_LOCKOUT_MS)
        self._press_stops = self._down

    # -- running a program (main thread) ------------------------------------------------------

    def run_program(self, trigger="host run", path=None, reraise_interrupt=True, name=None):
        """Run the staged program here and now, logged and framed; returns the outcome.

        `name` is the program's own file name (a source file staged as /program.py), which its
        tracebacks show; bytecode carries the name it was compiled with.

        The outcome is "finished", "stopped" (KeyboardInterrupt: button or Ctrl-C) or "error".
        With `reraise_interrupt` a stop propagates as KeyboardInterrupt once the run is logged, so a
        host console sees the program end the way Ctrl-C ends any raw-REPL command.
        """
        if _running[0]:
            raise RuntimeError("a program is already running; stop it with the program button first")
        path = resolve_program(path or self.program_path)
        if name is None and path.endswith(".py"):
            name = _staged_name(path)
        gc.collect()
        free = gc.mem_free() if hasattr(gc, "mem_free") else "n/a"
        claims = pins.snapshot()
        halts = estop.mark()
        estop.clear(halts)
        interrupted = None
        outcome = "error"
        stopped_by = None
        with log.session(self.log_dir) as run_log:
            self._started_ms = time.ticks_ms()
            log.write_text(
                "started: %s | firmware %s | program %s | uptime %d ms | free %s B"
                % (trigger, openbricks.firmware_label(), path, self._started_ms, free)
            )
            self._stop_pressed_ms = None
            self._halts_mark = halts
            log.reset_printed()
            _set_running(True)
            try:
                _execute(path, name)
                outcome = "finished"
                _set_running(False)
                self._wind_down()
                log.write_text("stopped: finished after %d ms" % self._elapsed_ms())
            except KeyboardInterrupt as exc:
                outcome = "stopped"
                stopped_by = "console" if self._stop_pressed_ms is None else "button"
                interrupted = exc
                _set_running(False)
                self._wind_down()
                log.write_text("stopped: KeyboardInterrupt (%s)" % self._stop_story())
            except BaseException as exc:  # noqa: BLE001 - SystemExit too: the run ends, the hub lives on
                outcome = "error"
                _set_running(False)
                self._wind_down()  # before the traceback: printing it over BLE takes a while
                text = traceback_text(exc) + _advice(exc, free)
                log.print_framing(text)
                log.write_text("stopped: %s after %d ms" % (_exception_line(exc), self._elapsed_ms()))
            finally:
                _last_end[0] = (run_log.index, outcome, trigger, stopped_by)
                _set_running(False)
                self._wind_down()  # if an interrupt landed before a branch above got to it
                estop.clear(halts)
                pins.release_since(claims)
                if self._stop_pressed_ms is not None:
                    self._lockout_until_ms = time.ticks_add(time.ticks_ms(), self.START_LOCKOUT_MS)
                self._stop_pressed_ms = None
                self._started_ms = None
        gc.collect()
        if interrupted is not None and reraise_interrupt:
            raise interrupted
        return outcome

    def _wind_down(self):
        """Release the finished program's hardware once per run, noting failures in its log."""
        halts = self._halts_mark
        if halts is None:
            return
        # Marked done only once it completed: a late stop retry landing halfway through unwinds to
        # a caller that winds down again, rather than skipping what was left.
        for line in _release_program_hardware(halts):
            log.write_text(line)
        self._halts_mark = None

    def _elapsed_ms(self):
        return time.ticks_diff(time.ticks_ms(), self._started_ms)

    def _stop_story(self):
        if self._stop_pressed_ms is None:
            self.note_external_stop()
            return "Ctrl-C from the console"
        return "%d ms after press, %d retries" % (
            time.ticks_diff(time.ticks_ms(), self._stop_pressed_ms),
            self._stop_retries,
        )

    def idle(self, duration_ms=None, on_run_end=None):
        """Serve button starts in this (main) thread: forever, or for `duration_ms`.

        A console Ctrl-C while idle ends this loop (the host takes the hub); one during a run only
        ends the run. `on_run_end(outcome)` is called once each button run is over and logged
        (a host watching the hub learns how it ended without racing the run's wrap-up).
        """
        began = time.ticks_ms()
        self._idling = True
        try:
            while duration_ms is None or time.ticks_diff(time.ticks_ms(), began) < duration_ms:
                if self._start_requested:
                    self._start_requested = False
                    outcome = None
                    try:
                        outcome = self.run_program("button press", reraise_interrupt=False)
                    except KeyboardInterrupt:
                        # A stop retry that landed while the finished run was being torn down:
                        # the run is over either way, and the hub must keep serving the button.
                        outcome = "stopped"
                    except Exception as exc:  # noqa: BLE001 - the run never started
                        # Nothing staged yet, or no room for the run log: say why on the console and
                        # keep serving the button (leaving this loop would leave the hub at the REPL
                        # with a program button that refuses every start until a reset).
                        print("program button: no run started: %s" % _exception_line(exc))
                    if outcome is not None and on_run_end is not None:
                        on_run_end(outcome)
                time.sleep_ms(self.poll_ms)
        finally:
            self._idling = False


def get(
    button_pin=DEFAULT_BUTTON_PIN,
    program_path=DEFAULT_PROGRAM_PATH,
    poll_ms=DEFAULT_POLL_MS,
    timer_id=DEFAULT_TIMER_ID,
    log_dir=log.LOG_DIR,
):
    """The hub's launcher, created with its watcher timer on first use (later arguments are ignored)."""
    if _launcher[0] is None:
        launcher = Launcher(button_pin, program_path, poll_ms, log_dir)
        launcher.start_watcher(timer_id)
        _launcher[0] = launcher
    return _launcher[0]


def shutdown():
    """Stop the hub's watcher and hand back the program-button pin (to rewire it, or a soft reset)."""
    launcher = _launcher[0]
    if launcher is None:
        return
    _launcher[0] = None
    if launcher._timer is not None:
        launcher._timer.deinit()
        timers.release(launcher._timer_id, _TIMER_ROLE)
    if launcher.button_pin is not None:
        pins.release(launcher.button_pin, "launcher")


def reset_state():
    """Forget the hub's launcher, the running flag and the listeners (a soft reset; tests)."""
    shutdown()
    _running[0] = False
    _last_end[0] = None
    del _listeners[:]
    del _events[:]


def run(
    program_path=DEFAULT_PROGRAM_PATH, button_pin=DEFAULT_BUTTON_PIN, poll_ms=DEFAULT_POLL_MS, timer_id=0
):
    """Install the button watcher and serve button starts forever. Called from the frozen main.py."""
    get(button_pin, program_path, poll_ms, timer_id).idle()


def run_program(program_path=None):
    """Run the staged program now (the host's `openbricks run`); a stop propagates KeyboardInterrupt."""
    launcher = get()
    return launcher.run_program("host run", program_path)
