"""`openbricks run` against a virtual hub with programs that try to leave it: each gets a hub's answer
or hits a limit of the hub's process, the host is untouched, and the hub goes on serving."""

import os
import time

import pytest

from ...sim.test_run_process import HOST_OS
from .conftest import HubProcess, cli

pytestmark = pytest.mark.e2e

MARKER = "/tmp/openbricks-escaped-hub"


@pytest.fixture(scope="module")
def boxed(data_dir):
    process = HubProcess("Boxed", data_dir, "--memory-mb", "400", "--run-wall-limit-s", "3")
    yield process
    process.stop()


def run_on(boxed, tmp_path, source):
    program = tmp_path / "reach.py"
    program.write_text(source)
    started = time.monotonic()
    done = cli(boxed.env, "run", "-n", boxed.name, str(program))
    return done, time.monotonic() - started


@pytest.mark.parametrize(
    ("source", "message"),
    [
        ("import subprocess\n", "ImportError: no module named 'subprocess'"),
        ("import io\nprint(io.open('/etc/passwd').read())\n", "OSError: [Errno 2] ENOENT"),
        ("import os\nos.fork()\n", "AttributeError: module 'os' has no attribute 'fork'"),
        (HOST_OS + "['fork']()\n", "OSError: [Errno 1] Operation not permitted"),
        (HOST_OS + "['system']('touch " + MARKER + "')\n", None),
        ("blocks = []\nwhile True:\n    blocks.append(bytearray(50 * 1024 * 1024))\n", "MemoryError"),
        ("while True:\n    pass\n", "wall-clock limit of 3 s"),
    ],
    ids=[
        "import-subprocess",
        "io-open-etc-passwd",
        "os-fork",
        "escaped-fork",
        "escaped-system",
        "memory",
        "busy",
    ],
)
def test_a_program_on_a_virtual_hub_reaches_only_the_hub(boxed, tmp_path, source, message):
    done, took = run_on(boxed, tmp_path, source)
    if message is not None:
        assert done.returncode == 1, done.stderr
        assert message in done.stdout, done.stdout + done.stderr
    assert took < 60
    assert not os.path.exists(MARKER)
    # The hub is still there and serves the next program.
    after = cli(boxed.env, "run", "-n", boxed.name, "-c", "import sys; print(sys.implementation.name)")
    assert after.returncode == 0 and after.stdout == "micropython\n", after.stderr
