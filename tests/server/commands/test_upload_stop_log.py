"""upload then the button, stop, and the run logs, end to end against a virtual hub."""

import json
import re
import subprocess
import sys

import pytest

from openbricks_server.logview import local_time

from .conftest import cli

pytestmark = pytest.mark.e2e

FOREVER = "import time\nn = 0\nwhile True:\n    print('still going', n)\n    n += 1\n    time.sleep_ms(50)\n"


def test_upload_stages_for_the_button_without_running(env, hub, tmp_path):
    program = tmp_path / "mission.py"
    program.write_text("print('button mission')\n")
    runs_before = hub.control("status")["runs_started"]
    done = cli(env, "upload", "-n", "RobotA", str(program))
    assert done.returncode == 0, done.stderr
    assert "press the program button to start it" in done.stdout
    assert hub.control("status")["runs_started"] == runs_before  # staged, not run
    hub.press_button()
    log = cli(env, "log", "-n", "RobotA")
    assert "started: button press" in log.stdout and "button mission" in log.stdout


def test_upload_path_stores_the_file_verbatim(env, hub, tmp_path):
    data = tmp_path / "settings.json"
    data.write_bytes(b'{"speed": 300}\n')
    done = cli(env, "upload", "-n", "RobotA", "--path", "/settings.json", str(data))
    assert done.returncode == 0, done.stderr
    assert hub.flash_file("/settings.json") == b'{"speed": 300}\n'
    done = cli(env, "upload", "-n", "RobotA", "--path", "relative.txt", str(data))
    assert done.returncode == 2 and "absolute hub file path" in done.stderr


def test_stop_ends_a_button_started_program(env, hub, tmp_path):
    program = tmp_path / "forever.py"
    program.write_text(FOREVER)
    assert cli(env, "upload", "-n", "RobotA", str(program)).returncode == 0
    hub.press_button(until="started")
    done = cli(env, "stop", "-n", "RobotA")
    assert done.returncode == 0
    assert re.fullmatch(r"RobotA: stopped the program \(run \d+, started by button press\)\n", done.stdout)
    assert not hub.control("status")["running"]
    log = cli(env, "log", "-n", "RobotA")
    assert "still going 0" in log.stdout and "stopped: KeyboardInterrupt" in log.stdout
    again = cli(env, "stop", "-n", "RobotA")
    assert again.returncode == 0 and again.stdout == "RobotA: no program was running\n"


def test_stop_after_a_killed_run_says_it_stopped_the_program_left_running(env, hub, tmp_path):
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
        while "still going 2" not in process.stdout.readline():
            assert process.poll() is None, process.stderr.read()
        process.kill()  # kill -9: no chance to stop the program on the hub
        process.wait(timeout=10)
    finally:
        process.kill()
        process.stdout.close()
        process.stderr.close()
    assert hub.control("status")["running"]
    done = cli(env, "stop", "-n", "RobotA")
    assert done.returncode == 0, done.stderr
    assert re.fullmatch(r"RobotA: stopped the program \(run \d+, started by host run\)\n", done.stdout)
    assert not hub.control("status")["running"]


def test_log_list_and_a_chosen_run_with_local_time_stamps(env):
    done = cli(env, "run", "-n", "RobotA", "-c", "print('first')")
    assert done.returncode == 0
    listing = cli(env, "log", "-n", "RobotA", "--list")
    rows = re.findall(r"^run\s+(\d+)\s+(\d+) bytes$", listing.stdout, re.MULTILINE)
    assert rows and all(int(size) > 0 for _, size in rows)
    newest = int(rows[-1][0])
    as_json = json.loads(cli(env, "log", "-n", "RobotA", "--list", "--json").stdout)
    assert as_json[-len(rows):] == [{"index": int(i), "bytes": int(size)} for i, size in rows]
    chosen = cli(env, "log", "-n", "RobotA", "--run", str(newest))
    assert chosen.stdout == cli(env, "log", "-n", "RobotA").stdout
    first_line = chosen.stdout.splitlines()[0]
    assert first_line.endswith(f"-- run_{newest} --")
    # The hub's clock was set on connect: stamps are today, in local time, with milliseconds.
    stamp = re.match(r"^\[(\d{4}-\d\d-\d\d \d\d:\d\d:\d\d\.\d{3})\] ", first_line).group(1)
    import time

    assert stamp[:10] == local_time(int(time.time() * 1000))[:10]
    missing = cli(env, "log", "-n", "RobotA", "--run", "99999")
    assert (
        missing.returncode == 1
        and f"has no run 99999: no such run exists yet (the newest is run {newest})" in missing.stderr
    )
