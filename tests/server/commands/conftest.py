"""End-to-end fixtures: real virtual hub processes, and the `openbricks` CLI run as a user runs it.

Every hub and every CLI call has a timeout, and hubs are terminated (killed if they linger) when the
test module ends, so a hung hub fails a test instead of stalling the suite.
"""

import contextlib
import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from ..flash.conftest import fake_esptool  # noqa: F401 - shared fixture: flash runs a fake esptool here too

HUB_START_TIMEOUT_S = 60
CLI_TIMEOUT_S = 90


class HubProcess:
    def __init__(self, name: str, data_dir: Path, *extra: str):
        self.name = name
        self.data_dir = data_dir
        self.env = dict(os.environ, OPENBRICKS_DATA_DIR=str(data_dir))
        self.process = subprocess.Popen(
            [
                sys.executable,
                "-m",
                "openbricks_sim.virtual_hub",
                "--name",
                name,
                "--pty",
                "--speed",
                "max",
                *extra,
            ],
            stdout=subprocess.PIPE,
            stderr=subprocess.PIPE,
            env=self.env,
            text=True,
        )
        self.pty = self._first_line()
        self.directory = data_dir / "virtual-hubs" / name
        self._wait_discoverable()

    def _wait_discoverable(self) -> None:
        """Until the hub answers on its control socket, as `openbricks -n` will look for it."""
        deadline = time.monotonic() + HUB_START_TIMEOUT_S
        while True:
            try:
                if self.control("status").get("pty") == self.pty:
                    return
            except (OSError, ValueError):
                pass
            if time.monotonic() > deadline:
                self.stop()
                raise RuntimeError(f"virtual hub {self.name} never answered on its control socket")
            time.sleep(0.1)

    def _first_line(self) -> str:
        import selectors

        selector = selectors.DefaultSelector()
        selector.register(self.process.stdout, selectors.EVENT_READ)
        if not selector.select(timeout=HUB_START_TIMEOUT_S):
            self.stop()
            raise RuntimeError(f"virtual hub {self.name} did not start: {self.process.stderr.read()}")
        line = self.process.stdout.readline().strip()
        if not line.startswith("/dev/"):
            self.stop()
            raise RuntimeError(f"virtual hub {self.name} failed: {line} {self.process.stderr.read()}")
        control = self.process.stdout.readline().strip()
        self.control_socket = Path(control.removeprefix("control "))
        return line

    def control(self, op: str) -> dict:
        from openbricks_server.link.discovery import control

        return control(self.control_socket, {"op": op})

    def press_button(self, until: str = "finished", timeout_s: float = 30.0) -> None:
        """Click the program button and wait until the run it starts has begun (until="started") or
        also ended (until="finished"). Until then a host connecting would interrupt the launcher's
        idle loop before it picks the press up.

        The launcher ignores presses for a moment after a stop (contact bounce of the stopping press);
        a test clicks far sooner after its last command than a person would, so a press that started
        nothing within a second is repeated, as a person would press again.
        """
        before = self.control("status")["runs_started"]
        self.control("click")
        clicked = time.monotonic()
        deadline = clicked + timeout_s
        status = {}
        while time.monotonic() < deadline:
            status = self.control("status")
            if status["runs_started"] > before and (until == "started" or not status["running"]):
                return
            if status["runs_started"] == before and time.monotonic() - clicked > 1.0:
                self.control("click")
                clicked = time.monotonic()
            time.sleep(0.05)
        raise AssertionError(
            f"the button press on {self.name} did not {until[:-2]} a run in {timeout_s} s "
            f"(runs started before: {before}; status now: {status})"
        )

    def nvs_blob(self, namespace: str, key: str) -> bytes | None:
        """A committed NVS blob of the hub, read from the file the virtual hub keeps it in."""
        import base64

        namespaces = json.loads((self.directory / "nvs.json").read_text())["namespaces"]
        item = namespaces.get(namespace, {}).get(key)
        return None if item is None else base64.b64decode(item["blob"])

    def flash_file(self, path: str) -> bytes:
        return (self.directory / "flash" / path.lstrip("/")).read_bytes()

    def stop(self) -> None:
        if self.process.poll() is None:
            self.process.terminate()
            try:
                self.process.wait(timeout=5)
            except subprocess.TimeoutExpired:
                self.process.kill()
                self.process.wait(timeout=5)
        for stream in (self.process.stdout, self.process.stderr):
            stream.close()


def cli(env: dict, *args: str, timeout: float = CLI_TIMEOUT_S, cwd=None) -> subprocess.CompletedProcess:
    return subprocess.run(
        [sys.executable, "-m", "openbricks_server.cli", *args],
        capture_output=True,
        text=True,
        env=env,
        timeout=timeout,
        cwd=cwd,
    )


def interrupt_when(
    process: subprocess.Popen, seen: str, timeout_s: float = 60, signal_number: int = signal.SIGINT
) -> str:
    """Read the CLI's stdout until `seen` appears, then Ctrl-C it (or send `signal_number`); returns
    what was read."""
    got = ""
    deadline = time.monotonic() + timeout_s
    while seen not in got:
        if time.monotonic() > deadline:
            process.kill()
            raise AssertionError(f"never saw {seen!r}; got {got!r}")
        line = process.stdout.readline()
        if not line and process.poll() is not None:
            raise AssertionError(f"the CLI ended before {seen!r}: {got!r} {process.stderr.read()}")
        got += line
    process.send_signal(signal_number)
    return got


@contextlib.contextmanager
def console_holding(env: dict, port: str, root: Path, timeout_s: float = 60):
    """`openbricks console` holding the hub on serial `port` (and no other hub); yields its URL."""
    env = dict(env, OPENBRICKS_RUNTIME_DIR=str(root / "run"))
    command = ["console", "--port", "0", "--virtual", "0", "--no-ble", "--data-dir", str(root / "console")]
    console = subprocess.Popen(
        [sys.executable, "-m", "openbricks_server.cli", *command, "--serial", port],
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
        env=env,
    )
    try:
        runtime = root / "run" / "console.json"
        deadline = time.monotonic() + timeout_s
        while not runtime.exists():
            assert console.poll() is None and time.monotonic() < deadline, "the console did not start"
            time.sleep(0.1)
        yield json.loads(runtime.read_text())["url"], env
    finally:
        console.send_signal(signal.SIGINT)
        try:
            console.wait(30)
        except subprocess.TimeoutExpired:
            console.kill()
            console.wait()


@pytest.fixture(scope="module")
def data_dir(tmp_path_factory):
    return tmp_path_factory.mktemp("openbricks-data")


@pytest.fixture(scope="module")
def hub(data_dir):
    process = HubProcess("RobotA", data_dir)
    yield process
    process.stop()


@pytest.fixture
def env(hub):
    return hub.env


@pytest.fixture
def board(tmp_path):
    """A hub of its own for one test, as a board on a USB port is: its pty stands in for the port."""
    process = HubProcess("Board01", tmp_path / "boards")
    yield process
    process.stop()
