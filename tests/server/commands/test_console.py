"""`openbricks console` as a user runs it: it prints the sign-in URL, publishes the runtime file (0600) for
the CLI, answers on it, and Ctrl-C stops it cleanly and removes the file."""

import json
import os
import re
import signal
import stat
import subprocess
import sys
import time

import httpx
import pytest

START_TIMEOUT_S = 60


@pytest.mark.e2e
def test_console_starts_prints_its_url_and_stops_cleanly_on_ctrl_c(tmp_path):
    runtime = tmp_path / "run"
    env = dict(os.environ, OPENBRICKS_RUNTIME_DIR=str(runtime), OPENBRICKS_DATA_DIR=str(tmp_path / "data"))
    console = subprocess.Popen(
        [
            sys.executable,
            "-m",
            "openbricks_server.cli",
            "console",
            "--port",
            "0",
            "--virtual",
            "0",
            "--no-ble",
            "--data-dir",
            str(tmp_path / "console"),
        ],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        env=env,
    )
    try:
        first = console.stdout.readline()
        match = re.search(r"open (http://127\.0\.0\.1:(\d+))/\?token=(\S+)", first)
        assert match, first + console.stderr.read()
        url, token = match.group(1), match.group(3)
        info_path = runtime / "console.json"
        deadline = time.monotonic() + START_TIMEOUT_S
        while not info_path.exists() and time.monotonic() < deadline:
            time.sleep(0.05)
        assert stat.S_IMODE(info_path.stat().st_mode) == 0o600
        info = json.loads(info_path.read_text())
        assert (info["url"], info["token"], info["pid"]) == (url, token, console.pid)
        health = httpx.get(
            f"{url}/api/system/health", headers={"Authorization": f"Bearer {token}"}, timeout=10
        )
        assert health.json()["ok"]
        console.send_signal(signal.SIGINT)
        status = console.wait(30)
    finally:
        if console.poll() is None:
            console.kill()
    assert status in (0, 130)
    assert not info_path.exists()
    assert "Traceback" not in console.stderr.read()


def test_a_busy_port_is_one_clear_line(tmp_path):
    import socket

    with socket.socket() as taken:
        taken.bind(("127.0.0.1", 0))
        taken.listen()
        port = taken.getsockname()[1]
        done = subprocess.run(
            [
                sys.executable,
                "-m",
                "openbricks_server.cli",
                "console",
                "--port",
                str(port),
                "--virtual",
                "0",
                "--no-ble",
                "--data-dir",
                str(tmp_path),
            ],
            capture_output=True,
            text=True,
            timeout=60,
            env=dict(os.environ, OPENBRICKS_RUNTIME_DIR=str(tmp_path / "run")),
        )
    assert done.returncode == 1
    assert f"port {port} on 127.0.0.1 is in use" in done.stderr and "--port" in done.stderr
    assert "Traceback" not in done.stderr
