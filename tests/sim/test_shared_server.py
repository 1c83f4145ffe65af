"""`openbricks sim run` and the shared warm server (sim/shared_server.py): the first run starts it, the
runs and sweeps after it are its children (in the command's folder, on its streams, fenced as any
child), and it ends when its socket is taken away; a folder others may enter gets no server at all."""

import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from openbricks_sim import shared_server
from openbricks_sim.job import SimJob
from openbricks_sim.sweep import sweep

SERVER_START_S = 90  # its imports and one 3D view, on a busy machine
CLI = [sys.executable, "-m", "openbricks_server.cli", "sim", "run"]


def test_a_folder_others_may_enter_gets_no_server(tmp_path, monkeypatch):
    monkeypatch.setenv(shared_server.RUNTIME_DIR_ENV, str(tmp_path))
    (tmp_path / "sim").mkdir(mode=0o755)
    os.chmod(tmp_path / "sim", 0o755)
    assert shared_server.socket_path() is None
    os.chmod(tmp_path / "sim", 0o700)
    assert shared_server.socket_path().startswith(str(tmp_path / "sim"))


def test_the_servers_name_follows_the_newest_source_file(tmp_path):
    (tmp_path / "pkg" / "__pycache__").mkdir(parents=True)
    (tmp_path / "pkg" / "a.py").write_text("", encoding="utf-8")
    (tmp_path / "pkg" / "__pycache__" / "a.cpython-311.pyc").write_bytes(b"")
    os.utime(tmp_path / "pkg" / "a.py", ns=(1_000_000_000, 1_000_000_000))
    assert shared_server._newest_py_ns(str(tmp_path)) == 1_000_000_000  # compiled files do not count
    os.utime(tmp_path / "pkg" / "a.py", ns=(2_000_000_000, 2_000_000_000))
    assert shared_server._newest_py_ns(str(tmp_path)) == 2_000_000_000


@pytest.fixture
def warm(tmp_path):
    """An environment with warm runs on, in a runtime folder of its own; its server is stopped after."""
    runtime = tmp_path / "run"
    env = dict(os.environ, OPENBRICKS_SIM_WARM="1", OPENBRICKS_RUNTIME_DIR=str(runtime))
    yield env
    for lock in (runtime / "sim").glob("*.lock"):
        pid = shared_server.server_pid(str(lock)[: -len(".lock")])
        if pid is not None:
            try:
                os.kill(pid, signal.SIGKILL)
            except ProcessLookupError:
                pass


def _sim_run(env, cwd, *args):
    done = subprocess.run(
        [*CLI, *args, "--json"], cwd=cwd, env=env, capture_output=True, text=True, timeout=120
    )
    return done, json.loads(done.stdout.strip().splitlines()[-1])


def _published(runtime: Path) -> Path:
    deadline = time.monotonic() + SERVER_START_S
    while time.monotonic() < deadline:
        sockets = list((runtime / "sim").glob("*.sock"))
        if sockets:
            return sockets[0]
        time.sleep(0.1)
    raise AssertionError(f"no warm server published within {SERVER_START_S} s")


@pytest.mark.e2e
def test_the_first_run_starts_the_server_and_the_next_runs_are_its_children(warm, tmp_path, monkeypatch):
    (tmp_path / "drive.py").write_text(
        "from openbricks.drivers.st3032 import ST3032Motor\n"
        "from openbricks.robotics import DriveBase\n"
        "left = ST3032Motor(servo_id=1, uart_id=1, tx=14, rx=41)\n"
        "right = ST3032Motor(servo_id=2, uart_id=1, tx=14, rx=41, invert=True)\n"
        "DriveBase(left, right, wheel_diameter_mm=88, axle_track_mm=136).straight(100)\n"
        "print('drove')\n",
        encoding="utf-8",
    )
    cold_done, cold = _sim_run(warm, tmp_path, "drive.py")
    assert cold_done.returncode == 0 and cold["output"] == "drove\n", cold_done.stderr
    socket_file = _published(Path(warm["OPENBRICKS_RUNTIME_DIR"]))

    # A relative path: the child works in the command's folder, not the server's.
    warm_done, warm_run = _sim_run(warm, tmp_path, "drive.py")
    assert warm_done.returncode == 0 and warm_run["output"] == "drove\n", warm_done.stderr
    assert warm_run["pose"] == pytest.approx(cold["pose"], abs=1e-6)  # the same run, to the micrometre
    assert warm_run["build_s"] < cold["build_s"] / 2  # MuJoCo was already loaded: a child of the server

    # The same fence as any child: the hub's imports only.
    (tmp_path / "escape.py").write_text("import subprocess\n", encoding="utf-8")
    fenced_done, fenced = _sim_run(warm, tmp_path, "escape.py")
    assert fenced_done.returncode != 0 and "subprocess" in fenced["error"]

    # A sweep finds it too: its seeds are the server's children.
    for name in ("OPENBRICKS_SIM_WARM", "OPENBRICKS_RUNTIME_DIR"):
        monkeypatch.setenv(name, warm[name])
    rows = list(sweep(SimJob(str(tmp_path / "drive.py")), [1, 2]))
    assert [row.result.output for row in rows] == ["drove\n", "drove\n"]
    assert all(row.result.build_s < cold["build_s"] / 2 for row in rows)

    # Its socket taken away, the server ends.
    pid = shared_server.server_pid(str(socket_file))
    socket_file.unlink()
    deadline = time.monotonic() + 10
    while time.monotonic() < deadline and Path(f"/proc/{pid}").exists():
        time.sleep(0.1)
    assert not Path(f"/proc/{pid}").exists() or "Z" in Path(f"/proc/{pid}/stat").read_text().split()[2]
