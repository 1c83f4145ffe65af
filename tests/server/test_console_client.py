"""The CLI through a running console: `openbricks console` started as a user starts it, then
`openbricks run/upload/log/stop/list` as separate processes go through its API (it holds the hubs'
links and locks) with the direct commands' output and exit statuses."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time

import pytest

pytestmark = pytest.mark.e2e

CLI_TIMEOUT_S = 90
FOREVER = (
    "from openbricks.tools import wait\nn = 0\nwhile True:\n    print('loop', n)\n    n += 1\n    wait(100)\n"
)


@pytest.fixture(scope="module")
def console(tmp_path_factory):
    root = tmp_path_factory.mktemp("console")
    env = dict(os.environ, OPENBRICKS_RUNTIME_DIR=str(root / "run"), OPENBRICKS_DATA_DIR=str(root / "data"))
    process = subprocess.Popen(
        [
            sys.executable,
            "-m",
            "openbricks_server.cli",
            "console",
            "--port",
            "0",
            "--virtual",
            "1",
            "--no-ble",
        ],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        env=env,
        text=True,
    )
    runtime = root / "run" / "console.json"
    deadline = time.monotonic() + 60
    while not runtime.exists():
        if process.poll() is not None or time.monotonic() > deadline:
            process.kill()
            raise RuntimeError(f"the console did not start: {process.stderr.read()}")
        time.sleep(0.1)
    info = json.loads(runtime.read_text())
    assert oct(runtime.stat().st_mode & 0o777) == "0o600"
    _wait_idle(env, info)
    yield env
    process.send_signal(signal.SIGINT)
    try:
        process.wait(30)
    except subprocess.TimeoutExpired:
        process.kill()
        raise
    assert not runtime.exists()  # the console removed its file on the way out


def _wait_idle(env, info):
    import httpx

    deadline = time.monotonic() + 60
    while time.monotonic() < deadline:
        hubs = httpx.get(
            info["url"] + "/api/hubs", headers={"Authorization": f"Bearer {info['token']}"}, timeout=10
        ).json()["hubs"]
        if hubs and all(hub["status"] == "idle" for hub in hubs):
            return
        time.sleep(0.2)
    raise AssertionError(f"the console's hubs did not come up: {hubs}")


def cli(env, *args):
    return subprocess.run(
        [sys.executable, "-m", "openbricks_server.cli", *args],
        capture_output=True,
        text=True,
        timeout=CLI_TIMEOUT_S,
        env=env,
    )


def test_run_goes_through_the_console_with_the_direct_output_and_status(console, tmp_path):
    program = tmp_path / "hello.py"
    program.write_text("print('hello from', 'the hub')\nfor i in range(3):\n    print('tick', i)\n")
    done = cli(console, "run", "-n", "SimHub-1", str(program))
    assert done.returncode == 0, done.stderr
    assert done.stdout == "hello from the hub\ntick 0\ntick 1\ntick 2\n"
    assert done.stderr.splitlines()[0].startswith("SimHub-1: firmware 2.7.1")
    crash = cli(console, "run", "-n", "SimHub-1", "-c", "print('before')\nvalue = {}['missing']\n")
    assert crash.returncode == 1
    assert crash.stdout.startswith("before\n") and "KeyError: 'missing'" in crash.stdout
    assert "the program ended with an error" in crash.stderr
    bad = cli(console, "run", "-n", "SimHub-1", "-c", "print('x'\n")
    assert bad.returncode == 1 and "<code>:1: SyntaxError" in bad.stderr and "Traceback" not in bad.stderr
    unknown = cli(console, "run", "-n", "NoSuchHub", "-c", "print(1)")
    assert unknown.returncode == 1 and "no hub 'NoSuchHub'" in unknown.stderr


def test_list_upload_log_and_stop_go_through_the_console(console, tmp_path):
    listed = cli(console, "list")
    assert listed.returncode == 0 and listed.stdout.split()[:3] == ["SimHub-1", "virtual", "virtual:SimHub-1"]
    program = tmp_path / "staged.py"
    program.write_text("print('staged and logged')\n")
    uploaded = cli(console, "upload", "-n", "SimHub-1", str(program))
    assert uploaded.returncode == 0, uploaded.stderr
    assert (
        uploaded.stdout
        == "staged staged.py at /program.py on SimHub-1: press the program button to start it\n"
    )
    ran = cli(console, "run", "-n", "SimHub-1", str(program))
    assert ran.returncode == 0
    listing = cli(console, "log", "-n", "SimHub-1", "--list")
    assert listing.returncode == 0 and listing.stdout.startswith("run ")
    shown = cli(console, "log", "-n", "SimHub-1")
    assert (
        shown.returncode == 0
        and "] staged and logged\n" in shown.stdout
        and "] started: host run" in shown.stdout
    )
    stopped = cli(console, "stop", "-n", "SimHub-1")
    assert stopped.returncode == 0 and stopped.stdout == "SimHub-1: no program was running\n"


def test_ctrl_c_on_a_run_through_the_console_stops_it_and_waits_for_the_confirmation(console, tmp_path):
    program = tmp_path / "forever.py"
    program.write_text(FOREVER)
    process = subprocess.Popen(
        [sys.executable, "-m", "openbricks_server.cli", "run", "-n", "SimHub-1", str(program)],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        env=console,
    )
    assert process.stdout.readline() == "loop 0\n"  # running on the hub, through the console
    process.send_signal(signal.SIGINT)
    out, err = process.communicate(timeout=CLI_TIMEOUT_S)
    assert process.returncode == 130, err
    assert "^C: stopping the program on SimHub-1 ..." in err
    assert "stopped: SimHub-1 confirmed the program ended" in err
    assert "Traceback" not in err
