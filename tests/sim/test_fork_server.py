"""A warm fork server's children: they run their job, end as they should, and are fenced in exactly
as a spawned child is (limits, the seccomp fence, the hub's imports)."""

import os
import socket
import threading
import time

import pytest

from openbricks_sim.fork_server import ForkServer
from openbricks_sim.forked import ForkServerError
from openbricks_sim.job import ERROR, FINISHED, MEMORY_LIMIT, STOPPED, SimJob
from openbricks_sim.run_process import run_in_child
from tests.sim.test_run_process import HOST_OS, MEMORY_BOMB, SLEEPY_LOOP

pytestmark = [pytest.mark.e2e, pytest.mark.skipif(not hasattr(os, "fork"), reason="fork() is POSIX")]


@pytest.fixture(scope="module")
def server():
    with ForkServer() as forker:
        yield forker


def run(server, tmp_path, source, **fields):
    program = tmp_path / "program.py"
    program.write_text(source, encoding="utf-8")
    return run_in_child(SimJob(str(program), **fields), quiet=True, forker=server)


def test_a_child_runs_its_program_and_drives_the_robot(server, tmp_path):
    source = (
        "from openbricks.drivers.st3032 import ST3032Motor\n"
        "from openbricks.robotics import DriveBase\n"
        "left = ST3032Motor(servo_id=1)\n"
        "right = ST3032Motor(servo_id=2, invert=True)\n"
        "DriveBase(left, right, wheel_diameter_mm=88, axle_track_mm=138).straight(300)\n"
        "print('there')\n"
    )
    result, status = run(server, tmp_path, source)
    assert (result.exit, status, result.output) == (FINISHED, 0, "there\n"), result.error
    assert abs(result.pose["x_mm"] - 300) < 2
    assert result.build_s is not None and result.build_s < 1.0, "MuJoCo was imported by the server"


def test_children_meet_the_memory_limit(server, tmp_path):
    result, status = run(server, tmp_path, MEMORY_BOMB, memory_mb=400)
    assert result.exit == MEMORY_LIMIT and status == 3
    assert "memory limit: the program ran out of its 400 MB" in result.error


@pytest.mark.parametrize(
    ("source", "message"),
    [
        ("import subprocess\n", "ImportError: no module named 'subprocess'"),
        (HOST_OS + "['fork']()\n", "OSError: [Errno 1] Operation not permitted"),
        ("print(open('../../../etc/passwd').read())\n", "OSError: [Errno 2] ENOENT"),
    ],
    ids=["hub-imports", "seccomp-fork", "flash-only-files"],
)
def test_children_reach_only_the_hub(server, tmp_path, source, message):
    result, _status = run(server, tmp_path, source)
    assert result.exit == ERROR and message in result.error


def test_a_stop_reaches_the_child(server, tmp_path):
    stop = threading.Event()
    threading.Timer(1.0, stop.set).start()
    program = tmp_path / "program.py"
    program.write_text(SLEEPY_LOOP, encoding="utf-8")
    result, status = run_in_child(
        SimJob(str(program), limit_ms=10**9), quiet=True, stop=stop, forker=server
    )
    assert result.exit == STOPPED and result.output == "started\n" and result.sim_ms > 0


def test_a_bad_request_is_refused_in_words(server):
    with pytest.raises(ForkServerError, match="unknown target 'shell'"):
        server.request("shell", [], [0, 1, 2])


def test_the_server_ends_when_its_requester_closes_it():
    forker = ForkServer()
    pid = forker.process.pid
    started = time.monotonic()
    forker.close()
    assert forker.process.returncode == 0 and time.monotonic() - started < 30
    with pytest.raises(ProcessLookupError):
        os.kill(pid, 0)
    with pytest.raises(OSError):
        socket.send_fds(forker.control, [b"{}"], [0])
