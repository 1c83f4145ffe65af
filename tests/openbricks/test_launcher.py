"""Whole runs through the launcher: started by the program button (GPIO 39), printing, failing,
stopped by the button, rotating past ten runs, capped, and read back with read_run."""

import time

import machine

from fakes import clock, tmpdir
from fakes.expect import raises
from openbricks import estop, launcher, log, pins

BUTTON = 39


def _stage(directory, source, name="program.py"):
    path = directory + "/" + name
    with open(path, "w") as f:
        f.write(source)
    return path


def _at(ms, fn):
    """Do `fn()` when the virtual clock reaches `ms` from now (a press scheduled into the future)."""
    clock.after_ms(ms, fn)


def _press(at_ms, hold_ms=150):
    _at(at_ms, lambda: machine.board.set_input(BUTTON, 0))
    _at(at_ms + hold_ms, lambda: machine.board.set_input(BUTTON, 1))


def _hub(directory, source, **kwargs):
    path = _stage(directory, source)
    hub = launcher.Launcher(BUTTON, path, log_dir=directory + "/logs", **kwargs)
    hub.start_watcher(0)
    return hub


def _log_lines(directory, index=None):
    runs = log.list_runs(directory + "/logs")
    if index is None:
        index = runs[-1][0]
    lines = log.read_run(index, directory + "/logs").rstrip("\n").split("\n")
    return [line.split(" ", 1)[1] for line in lines]  # drop the epoch stamps


def test_button_press_runs_the_program_and_its_prints_land_in_the_log():
    with tmpdir.scratch() as directory:
        hub = _hub(
            directory,
            "from openbricks.tools import wait\nfor i in range(3):\n    print('lap', i)\n    wait(100)\n",
        )
        _press(100)
        hub.idle(2000)
        lines = _log_lines(directory)
        assert lines[0] == "-- run_0 --"
        assert lines[1].startswith("started: button press | firmware 2.7.1 (")
        assert "| program %s/program.py | uptime " % directory in lines[1]
        assert lines[2:5] == ["lap 0", "lap 1", "lap 2"]
        assert lines[5] == "stopped: finished after 300 ms"
        assert not launcher.program_running()


def test_an_exception_leaves_its_full_traceback_in_the_log():
    with tmpdir.scratch() as directory:
        source = "def drive(n):\n    return 100 // n\n\nprint('before')\ndrive(0)\n"
        hub = _hub(directory, source)
        _press(100)
        hub.idle(1000)
        text = "\n".join(_log_lines(directory))
        assert "before" in text
        assert "Traceback (most recent call last):" in text
        assert 'program.py", line 5' in text  # the call site
        assert 'program.py", line 2' in text  # and where it failed, inside drive()
        assert "ZeroDivisionError" in text
        assert _log_lines(directory)[-1].startswith("stopped: ZeroDivisionError")


def test_a_host_run_traceback_names_the_users_file_and_shows_only_its_frames():
    with tmpdir.scratch() as directory:
        source = (
            "from openbricks.tools import plot\n\ndef build():\n    plot('speed', float('nan'))\n\nbuild()\n"
        )
        hub = _hub(directory, source)
        assert hub.run_program("host run", name="mission.py", reraise_interrupt=False) == "error"
        lines = _log_lines(directory)
        start = lines.index("Traceback (most recent call last):")
        assert lines[start + 1 : start + 3] == [
            '  File "mission.py", line 6, in <module>',
            '  File "mission.py", line 4, in build',
        ]
        assert lines[start + 3] == "ValueError: plot() value must be finite, got nan"
        assert not any("openbricks/" in line or "program.py" in line for line in lines[start:])


def test_user_frames_drops_the_runtimes_frames_wherever_the_runtime_lives():
    text = (
        "Traceback (most recent call last):\n"
        '  File "openbricks/launcher.py", line 426, in run_program\n'
        '  File "/lib/openbricks/robotics/drivebase.py", line 80, in __init__\n'
        '  File "mission.py", line 4, in build\n'
        '  File "/lib/helpers.py", line 2, in go\n'
        "ValueError: no\n"
    )
    assert launcher.user_frames(text) == (
        "Traceback (most recent call last):\n"
        '  File "mission.py", line 4, in build\n'
        '  File "/lib/helpers.py", line 2, in go\n'
        "ValueError: no\n"
    )


def test_stop_press_engages_the_estop_and_frames_the_stop_in_the_log():
    with tmpdir.scratch() as directory:
        source = (
            "from openbricks import estop\n"
            "from openbricks.tools import wait\n"
            "estop.on_engage(lambda: print('motors halted'))\n"
            "n = 0\n"
            "while True:\n"
            "    n += 1\n"
            "    print('tick', n)\n"
            "    wait(100)\n"
        )
        hub = _hub(directory, source)
        _press(100)  # start on release at ~350 ms
        _press(1500)  # stop on press-down
        hub.idle(3000)
        lines = _log_lines(directory)
        stop_at = lines.index("button pressed -> stop")
        assert lines[stop_at + 1 : stop_at + 3] == ["motors halted", "estop engaged"]
        assert lines[-1] == "stopped: KeyboardInterrupt (0 ms after press, 0 retries)"
        assert len(log.list_runs(directory + "/logs")) == 1  # the stopping press did not restart it
        assert not estop.engaged()


def test_a_program_that_swallows_the_interrupt_is_retried_until_dead():
    with tmpdir.scratch() as directory:
        source = (
            "import time\n"
            "survived = 0\n"
            "while True:\n"
            "    try:\n"
            "        time.sleep_ms(10)\n"
            "    except KeyboardInterrupt:\n"
            "        survived += 1\n"
            "        print('swallowed', survived)\n"
            "        if survived == 3:\n"
            "            raise\n"
        )
        hub = _hub(directory, source)
        _press(100)
        _press(1000)
        hub.idle(4000)
        lines = _log_lines(directory)
        assert "swallowed 3" in lines
        # The press lands at 1100 ms; retries follow every 300 ms.
        assert lines[-1] == "stopped: KeyboardInterrupt (600 ms after press, 2 retries)"


def test_the_stopping_press_and_its_bounce_never_restart_the_robot():
    with tmpdir.scratch() as directory:
        hub = _hub(directory, "from openbricks.tools import wait\nwhile True:\n    wait(50)\n")
        _press(100)
        _press(1000, hold_ms=400)  # a long stop press: its release must not start a new run
        _press(1500)  # bounce within the lockout after the stop: ignored
        hub.idle(2500)
        assert [i for i, _p in log.list_runs(directory + "/logs")] == [0]
        _press(100)  # a deliberate press later starts the program again
        _press(800)
        hub.idle(1500)
        assert [i for i, _p in log.list_runs(directory + "/logs")] == [0, 1]
        assert _log_lines(directory, 1)[1].startswith("started: button press")


def test_the_starting_press_chatter_never_starts_a_finished_program_again():
    with tmpdir.scratch() as directory:
        hub = _hub(directory, "print('done at once')\n")
        _press(100)  # released at 250, seen at ~350: the start
        _press(400, hold_ms=100)  # its chatter, released within START_PRESS_OPEN_MS: no second run
        hub.idle(1500)
        assert [i for i, _p in log.list_runs(directory + "/logs")] == [0]
        _press(100)  # a deliberate press later starts it again
        hub.idle(1000)
        assert [i for i, _p in log.list_runs(directory + "/logs")] == [0, 1]


def test_a_press_in_the_start_release_chatter_is_not_a_stop():
    with tmpdir.scratch() as directory:
        hub = _hub(directory, "from openbricks.tools import wait\nwait(1500)\nprint('ran to the end')\n")
        _press(100)  # start seen at ~350
        _press(700, hold_ms=100)  # down at ~800: past the run's start grace, inside RELEASE_CHATTER_MS
        hub.idle(3000)
        assert _log_lines(directory)[-1].startswith("stopped: finished")


def test_rotation_past_ten_runs_keeps_the_last_ten_readable():
    with tmpdir.scratch() as directory:
        hub = _hub(directory, "import time\nprint('run at', time.ticks_ms())\n")
        for _ in range(12):
            _press(100)
            hub.idle(900)
        runs = log.list_runs(directory + "/logs")
        assert [index for index, _path in runs] == list(range(2, 12))
        assert _log_lines(directory, 11)[0] == "-- run_11 --"
        assert _log_lines(directory, 11)[-1].startswith("stopped: finished")
        with raises(OSError, "run 1 is not on the hub"):
            log.read_run(1, directory + "/logs")


def test_a_runaway_printer_is_capped_at_64_kb_and_still_framed():
    with tmpdir.scratch() as directory:
        source = "from openbricks.tools import wait\nwhile True:\n    print('x' * 60)\n    wait(1)\n"
        hub = _hub(directory, source)
        _press(100)
        _press(2000)
        hub.idle(3000)
        text = log.read_run(0, directory + "/logs")
        assert 64 * 1024 < len(text) <= 65 * 1024
        assert "log capped at 65536 bytes" in text
        assert text.rstrip("\n").endswith("stopped: KeyboardInterrupt (0 ms after press, 0 retries)")


def test_host_run_streams_output_and_a_console_ctrl_c_propagates_after_logging():
    with tmpdir.scratch() as directory:
        hub = _hub(directory, "print('working')\nraise KeyboardInterrupt\n")
        with raises(KeyboardInterrupt):
            hub.run_program("host run")
        lines = _log_lines(directory)
        assert lines[1].startswith("started: host run |")
        assert lines[2] == "working"
        assert lines[-1] == "stopped: KeyboardInterrupt (Ctrl-C from the console)"


def test_running_state_is_signalled_to_listeners_and_program_claims_are_released():
    with tmpdir.scratch() as directory:
        source = (
            "from openbricks import launcher, pins\n"
            "pins.claim(5, 'HC-SR04 trig', owner='HCSR04')\n"
            "print('running:', launcher.program_running())\n"
        )
        hub = _hub(directory, source)
        seen = []
        launcher.add_listener(seen.append)
        try:
            assert hub.run_program() == "finished"
            assert hub.run_program() == "finished"  # GPIO 5 was handed back at the end of run 0
        finally:
            launcher.remove_listener(seen.append)
        assert seen == [True, False, True, False]
        assert "running: True" in _log_lines(directory)
        assert pins.owner_of(5) is None
        assert pins.owner_of(BUTTON) == ("program button", "launcher")


def test_a_press_while_a_console_session_holds_the_hub_starts_nothing():
    with tmpdir.scratch() as directory:
        _hub(directory, "print('must not run')\n")
        _press(100)
        time.sleep_ms(1000)  # the main thread is busy elsewhere (a host session), not in idle()
        assert log.list_runs(directory + "/logs") == []


def test_the_program_button_pin_is_guarded_and_a_missing_program_is_named():
    with tmpdir.scratch() as directory:
        hub = launcher.Launcher(BUTTON, directory + "/program.mpy", log_dir=directory + "/logs")
        with raises(pins.ReservedPinError, "in use as the program button (owner: launcher)"):
            pins.claim(BUTTON, "L298N IN1", owner="L298N")
        with raises(OSError, "no program staged at %s/program.mpy" % directory):
            hub.run_program()


def test_presses_are_acknowledged_on_the_status_led_and_kept_in_the_event_ring():
    from openbricks import bluetooth_button

    with tmpdir.scratch() as directory:
        hub = _hub(directory, "from openbricks.tools import wait\nwhile True:\n    wait(20)\n")
        acks = []
        real_notify = bluetooth_button.notify_press
        bluetooth_button.notify_press = lambda stop=False: acks.append("stop" if stop else "start")
        try:
            _press(100)
            _press(1000)
            hub.idle(2000)
        finally:
            bluetooth_button.notify_press = real_notify
        assert acks == ["start", "stop"]
        printed = []
        launcher.print = printed.append  # what dump_events() shows on the console
        try:
            launcher.dump_events()
        finally:
            del launcher.print
        shown = [line.split(" ms  ", 1)[1] for line in printed]
        assert shown == ["press (idle)", "release -> start", "press -> stop", "release of a stopping press"]


def test_a_re_uploaded_helper_module_is_loaded_fresh_on_the_next_run():
    with tmpdir.scratch() as directory:
        hub = _hub(directory, "import helper\nprint('helper says', helper.VALUE)\n")
        _stage(directory, "VALUE = 1\n", "helper.py")
        hub.run_program()
        # A different size too: CPython's bytecode cache trusts (mtime in s, size) of the source.
        _stage(directory, "VALUE = 22\n", "helper.py")
        hub.run_program()
        assert "helper says 1" in _log_lines(directory, 0)
        assert "helper says 22" in _log_lines(directory, 1)


def test_a_starved_watcher_tick_leaves_a_note_naming_the_gap():
    with tmpdir.scratch() as directory:
        hub = _hub(directory, "from openbricks.tools import wait\nwait(8000)\n")
        # A callback that blocks for 6 s holds every other timer back, like a long C call on the hub.
        _at(600, lambda: time.sleep_ms(6000))
        hub.run_program()
        notes = [line for line in _log_lines(directory) if line.startswith("watcher tick starved")]
        assert len(notes) == 1
        assert notes[0].startswith("watcher tick starved for 60")  # ~6000 ms, at poll granularity
        assert "(slowest log write " in notes[0]


_RUNAWAY_MOTOR = (
    "import time\n"
    "import machine\n"
    "from openbricks.drivers.l298n import L298NMotor\n"
    "motor = L298NMotor(in1=1, in2=2, pwm=17)\n"
    "motor.dc(60)\n"
)


def test_a_motor_left_running_is_halted_when_the_program_ends_or_fails():
    with tmpdir.scratch() as directory:
        hub = _hub(directory, _RUNAWAY_MOTOR + "print('driving', machine.board.pwms[17].duty_u16() > 0)\n")
        assert hub.run_program() == "finished"
        assert "driving True" in _log_lines(directory)
        assert machine.board.pwms[17].duty_u16() == 0  # no robot drives off the table after its program
        _stage(directory, _RUNAWAY_MOTOR + "print(1 // 0)\n")
        assert hub.run_program() == "error"
        assert machine.board.pwms[17].duty_u16() == 0


def test_the_stop_press_halts_motors_at_once_and_refuses_new_motion():
    with tmpdir.scratch() as directory:
        source = _RUNAWAY_MOTOR + (
            "try:\n"
            "    while True:\n"
            "        time.sleep_ms(10)\n"
            "except KeyboardInterrupt:\n"
            "    print('duty after the press', machine.board.pwms[17].duty_u16())\n"
            "    try:\n"
            "        motor.dc(60)\n"
            "    except KeyboardInterrupt as refusal:\n"
            "        print('refused:', refusal)\n"
            "    print('duty after a new command', machine.board.pwms[17].duty_u16())\n"
        )
        hub = _hub(directory, source)
        _press(100)
        _press(1000)
        hub.idle(2000)
        lines = _log_lines(directory)
        assert "duty after the press 0" in lines
        refusals = [line for line in lines if line.startswith("refused: ")]
        assert len(refusals) == 1 and "dc() refused: e-stop engaged (program button)" in refusals[0]
        assert "duty after a new command 0" in lines


def test_a_press_with_nothing_staged_is_explained_and_the_button_keeps_working():
    with tmpdir.scratch() as directory:
        hub = launcher.Launcher(BUTTON, directory + "/program.py", log_dir=directory + "/logs")
        hub.start_watcher(0)
        printed = []
        launcher.print = printed.append  # the console
        try:
            _press(100)  # a freshly flashed hub: nothing uploaded yet
            hub.idle(1000)
        finally:
            del launcher.print
        assert any("no program staged at %s/program.py" % directory in line for line in printed), printed
        _stage(directory, "print('uploaded later')\n")
        _press(100)
        hub.idle(1000)
        assert "uploaded later" in _log_lines(directory)


def test_the_stop_press_halts_the_motors_before_paying_for_a_log_commit():
    # A littlefs commit costs 60-90 ms on the hub: at 500 mm/s that is 40 mm more travel if the
    # framing line is committed before the motors are told to stop.
    with tmpdir.scratch() as directory:
        events = []
        source = (
            "from openbricks import estop, launcher, log\n"
            "from openbricks.tools import wait\n"
            "events = launcher.test_events\n"
            "session = log.active()\n"
            "real_flush = session.flush\n"
            "def flush():\n"
            "    events.append('commit')\n"
            "    real_flush()\n"
            "session.flush = flush\n"
            "estop.on_engage(lambda: events.append('halt'))\n"
            "events.append('running')\n"
            "while True:\n"
            "    wait(100)\n"
        )
        hub = _hub(directory, source)
        launcher.test_events = events
        try:
            _press(100)
            _press(1000)
            hub.idle(2000)
        finally:
            del launcher.test_events
        after_start = events[events.index("running") + 1 :]
        assert after_start[0] == "halt", events
        lines = _log_lines(directory)
        assert lines.index("button pressed -> stop") + 1 == lines.index("estop engaged")
