"""`openbricks console` started the way a user starts it, in its own process, for the browser tests and
the console_web benchmark: a free port on 127.0.0.1, its own data dir, the sign-in URL read from what
it prints."""

from __future__ import annotations

import os
import re
import signal
import socket
import subprocess
import sys
import time
from dataclasses import dataclass
from pathlib import Path

import httpx

from openbricks_server.daemon.routers import pages

START_TIMEOUT_S = 90.0


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


@dataclass
class Console:
    process: subprocess.Popen
    url: str  # the printed sign-in URL, with the operator token
    base: str
    token: str
    data_dir: Path

    def api(self) -> httpx.Client:
        """The REST API as a script uses it (Bearer token, no Origin)."""
        return httpx.Client(base_url=self.base, headers={"Authorization": f"Bearer {self.token}"}, timeout=15)

    def mint(self, role: str) -> str:
        with self.api() as c:
            r = c.post("/api/auth/tokens", json={"role": role})
            r.raise_for_status()
            return r.json()["token"]

    def run(self, api: httpx.Client, hub: str, program: str) -> None:
        """Start a stored program on a hub, as a script would."""
        api.post(f"/api/hubs/{hub}/run", json={"program": program}).raise_for_status()

    def open_runs(self, api: httpx.Client) -> list[dict]:
        return api.get("/api/runs", params={"outcome": "running", "limit": 1000}, timeout=60).json()

    def sign_in_url(self, token: str, page: str = "dashboard") -> str:
        return f"{self.base}/?token={token}#/{page}"

    def wait_hubs_idle(self, count: int, timeout_s: float = 60) -> list[dict]:
        deadline = time.monotonic() + timeout_s
        hubs: list[dict] = []
        with self.api() as c:
            while time.monotonic() < deadline:
                hubs = c.get("/api/hubs").json()["hubs"]
                if sum(h["status"] == "idle" for h in hubs) >= count:
                    return hubs
                time.sleep(0.3)
        raise AssertionError(f"{count} hubs did not become idle within {timeout_s} s: {hubs}")


def start_console(
    data_dir: Path, virtual: int = 2, extra: list[str] | None = None, port: int | None = None
) -> Console:
    """`port`: the one to listen on (a restart where the page left off), else a free one."""
    assert pages.INDEX.is_file(), "the console page is not built: run `make web` (make test does)"
    port = port or free_port()
    # Its own hub locks and virtual-hub folder too: consoles of tests running side by side never meet.
    env = {
        **os.environ,
        "PYTHONUNBUFFERED": "1",
        "XDG_RUNTIME_DIR": str(data_dir / "run"),
        "OPENBRICKS_DATA_DIR": str(data_dir / "state"),
    }
    (data_dir / "run").mkdir(parents=True, exist_ok=True)
    log = open(data_dir / "console.log", "w")  # noqa: SIM115 - closed with the process
    process = subprocess.Popen(
        [
            sys.executable,
            "-m",
            "openbricks_server.cli",
            "console",
            "--port",
            str(port),
            "--data-dir",
            str(data_dir),
            "--virtual",
            str(virtual),
            "--no-ble",
            *(extra or []),
        ],
        stdout=log,
        stderr=subprocess.STDOUT,
        env=env,
        start_new_session=True,
    )
    deadline = time.monotonic() + START_TIMEOUT_S
    url = None
    while time.monotonic() < deadline and url is None:
        if process.poll() is not None:
            raise AssertionError(f"openbricks console exited: {(data_dir / 'console.log').read_text()}")
        found = re.search(r"(http://127\.0\.0\.1:\d+)/\?token=(\S+)", (data_dir / "console.log").read_text())
        if found:
            url = found.group(0)
            base, token = found.group(1), found.group(2)
        else:
            time.sleep(0.2)
    if url is None:
        stop_console(process)
        raise AssertionError(
            f"no sign-in URL within {START_TIMEOUT_S} s: {(data_dir / 'console.log').read_text()}"
        )
    return Console(process, url, base, token, data_dir)


def stop_console(process: subprocess.Popen) -> None:
    if process.poll() is None:
        process.send_signal(signal.SIGINT)
        try:
            process.wait(timeout=20)
        except subprocess.TimeoutExpired:
            os.killpg(process.pid, signal.SIGKILL)
            process.wait(timeout=10)
