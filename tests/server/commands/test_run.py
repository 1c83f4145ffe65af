"""`openbricks run` end to end against a virtual hub: output, outcome, Ctrl-C, errors for users."""

import signal
import subprocess
import sys
import time

import pytest

from openbricks_server.hub_lock import hub_lock

from .conftest import cli, interrupt_when

pytestmark = pytest.mark.e2e

FOREVER = "import time\nn = 0\nwhile True:\n    print('loop', n)\n    n += 1\n    time.sleep_ms(100)\n"


def test_output_streams_after_a_banner_and_the_status_is_the_outcome(env, tmp_path):
    program = tmp_path / "hello.py"
    program.write_text("print('hello from', 'the hub')\nfor i in range(3):\n    print('tick', i)\n")
    done = cli(env, "run", "-n", "RobotA", str(program))
    assert done.returncode == 0, done.stderr
    assert done.stdout == "hello from the hub\ntick 0\ntick 1\ntick 2\n"
    assert "RobotA: firmware 2.7.1 (customized)" in done.stderr.splitlines()[0]
    assert "sending the source" in done.stderr  # a virtual hub loads no .mpy: announced, not silent


def test_a_program_error_shows_its_traceback_and_exits_1(env, tmp_path):
    program = tmp_path / "crash.py"
    program.write_text("print('before')\ndef look(key):\n    return {}[key]\nlook('missing')\n")
    done = cli(env, "run", "-n", "RobotA", str(program))
    assert done.returncode == 1
    # The user's file and lines, only the user's frames: not the staged /program.py, no launcher.
    assert done.stdout == (
        "before\n"
        "Traceback (most recent call last):\n"
        '  File "crash.py", line 4, in <module>\n'
        '  File "crash.py", line 3, in look\n'
        "KeyError: 'missing'\n"
    )
    assert "the program ended with an error (run " in done.stderr


def test_a_last_line_without_newline_and_imitated_result_lines_are_shown_as_printed(env):
    code = "print('@openbricks-result {\"ok\": true}')\nprint('@openbricks:- result {}')\nprint('x', end='')"
    done = cli(env, "run", "-n", "RobotA", "-c", code)
    assert done.returncode == 0, done.stderr
    assert done.stdout == '@openbricks-result {"ok": true}\n@openbricks:- result {}\nx'
    assert "printed no result" not in done.stderr


def test_inline_code(env):
    done = cli(env, "run", "-n", "RobotA", "-c", "import openbricks; print(openbricks.__version__)")
    assert done.returncode == 0 and done.stdout == "2.7.1\n"


def test_ctrl_c_stops_the_remote_program_and_the_hub_confirms(env, hub, tmp_path):
    program = tmp_path / "forever.py"
    program.write_text(FOREVER)
    process = subprocess.Popen(
        [sys.executable, "-m", "openbricks_server.cli", "run", "-n", "RobotA", str(program)],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        env=env,
    )
    try:
        interrupt_when(process, "loop 3")
        out, err = process.communicate(timeout=30)
    finally:
        process.kill()
    assert process.returncode == 130, err
    assert "stopping the program on RobotA" in err and "stopped: RobotA confirmed the program ended" in err
    assert "Traceback" not in err
    assert not hub.control("status")["running"]


@pytest.mark.parametrize("stop_signal", [signal.SIGTERM, signal.SIGHUP])
def test_sigterm_and_sighup_stop_the_remote_program_like_ctrl_c(env, hub, tmp_path, stop_signal):
    program = tmp_path / "forever.py"
    program.write_text(FOREVER)
    process = subprocess.Popen(
        [sys.executable, "-m", "openbricks_server.cli", "run", "-n", "RobotA", str(program)],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        env=env,
    )
    try:
        interrupt_when(process, "loop 3", signal_number=stop_signal)
        out, err = process.communicate(timeout=30)
    finally:
        process.kill()
    assert process.returncode == 130, err
    assert f"{stop_signal.name}: stopping the program on RobotA" in err
    assert "stopped: RobotA confirmed the program ended (run " in err
    assert not hub.control("status")["running"]


def test_the_run_leaves_the_program_staged_for_the_button(env, hub, tmp_path):
    program = tmp_path / "mission.py"
    program.write_text("print('mission', 42)\n")
    assert cli(env, "run", "-n", "RobotA", str(program)).returncode == 0
    hub.press_button()
    log = cli(env, "log", "-n", "RobotA")
    assert "started: button press" in log.stdout and "mission 42" in log.stdout


def test_syntax_errors_come_before_any_hub_is_looked_for(env, tmp_path):
    program = tmp_path / "typo.py"
    program.write_text("print('ok')\nif True\n    pass\n")
    started = time.perf_counter()
    done = cli(env, "run", "-n", "NoSuchHub", str(program))
    assert time.perf_counter() - started < 10
    assert done.returncode == 1
    assert "typo.py:2: SyntaxError: expected ':'" in done.stderr and "2 | if True" in done.stderr
    assert "NoSuchHub" not in done.stderr


def test_an_unknown_name_lists_the_hubs_seen(env, tmp_path):
    done = cli(env, "run", "-n", "RobotZ", "-c", "print(1)")
    assert done.returncode == 1
    assert "no hub named 'RobotZ'" in done.stderr and "virtual hubs: RobotA" in done.stderr
    assert "Traceback" not in done.stderr


def test_a_busy_hub_is_refused(env, monkeypatch, data_dir):
    monkeypatch.setenv("OPENBRICKS_DATA_DIR", str(data_dir))
    with hub_lock("RobotA"):
        done = cli(env, "run", "-n", "RobotA", "-c", "print(1)")
    assert done.returncode == 1 and "hub 'RobotA' is busy" in done.stderr


def test_missing_non_utf8_and_oversized_files_are_refused(env, tmp_path):
    assert "no such file" in cli(env, "run", "-n", "RobotA", str(tmp_path / "nope.py")).stderr
    latin = tmp_path / "latin.py"
    latin.write_bytes("print('é')\n".encode("latin-1"))
    assert "is not UTF-8" in cli(env, "run", "-n", "RobotA", str(latin)).stderr
    huge = tmp_path / "huge.py"
    huge.write_text("#" * (300 * 1024))
    assert "a hub takes programs up to" in cli(env, "run", "-n", "RobotA", str(huge)).stderr


def test_debug_dumps_every_packet_received_on_stderr(env):
    done = cli(env, "run", "-n", "RobotA", "--debug", "-c", "print('traced')")
    assert done.returncode == 0 and done.stdout == "traced\n"
    dumps = [line for line in done.stderr.splitlines() if line.startswith("[") and " B  " in line]
    text = "".join(line[line.index("|") + 1 : -1] for line in dumps)  # the packets' printable columns
    assert "traced" in text and "raw REPL; CTRL-B to exit" in text
