"""`openbricks sim run` runs the program in a child process under limits: what a user sees when a
program hits one, how the run is interrupted, and that the CLI process itself is never touched."""

import json
import os
import signal
import subprocess
import sys
import time

import pytest

# Past the hub's Python: the host's os module, reached through object internals.
HOST_OS = (
    "[c for c in ().__class__.__base__.__subclasses__() if c.__name__ == '_wrap_close'][0]"
    ".__init__.__globals__"
)
BUSY_LOOP = "print('spinning', end='')\nwhile True:\n    pass\n"
MEMORY_BOMB = "blocks = []\nwhile True:\n    blocks.append(bytearray(50 * 1024 * 1024))\n"
STUBBORN_LOOP = """\
while True:
    try:
        while True:
            pass
    except BaseException:
        pass
"""
SLEEPY_LOOP = "import time\nprint('started')\nwhile True:\n    time.sleep_ms(10)\n"


def sim_run(program, *args, timeout=120):
    """(completed process, wall seconds) of `openbricks sim run PROGRAM ARGS`."""
    started = time.monotonic()
    done = subprocess.run(
        [sys.executable, "-m", "openbricks_server.cli", "sim", "run", str(program), *args],
        capture_output=True,
        text=True,
        timeout=timeout,
    )
    return done, time.monotonic() - started


def write(tmp_path, name, source):
    path = tmp_path / name
    path.write_text(source)
    return path


@pytest.mark.e2e
def test_a_busy_loop_is_stopped_by_the_default_wall_limit_derived_from_duration(tmp_path):
    done, took = sim_run(write(tmp_path, "busy.py", BUSY_LOOP), "--duration", "1")
    assert done.returncode == 3, done.stderr
    assert done.stdout == "spinning"
    assert "wall-clock limit: the program ran 10 s of wall-clock time (--wall-limit)" in done.stderr
    assert "time.sleep_ms()" in done.stderr and "[wall_limit]" in done.stderr
    assert took < 30


@pytest.mark.e2e
def test_the_cpu_limit_stops_a_busy_loop_and_json_names_the_limit(tmp_path):
    done, took = sim_run(
        write(tmp_path, "busy.py", BUSY_LOOP), "--wall-limit", "0", "--cpu-limit", "2", "--json"
    )
    assert done.returncode == 3, done.stderr
    result = json.loads(done.stdout)
    assert result["exit"] == "cpu_limit" and result["output"] == "spinning"
    assert "CPU-time limit: the run's process used its 2 s of processor time" in result["error"]
    assert result["job"]["limits"] == {"wall_s": None, "cpu_s": 2.0, "memory_mb": 1024}
    assert took < 30


@pytest.mark.e2e
def test_a_memory_bomb_ends_in_the_memory_limit_and_the_cli_stays_small(tmp_path):
    done, took = sim_run(write(tmp_path, "bomb.py", MEMORY_BOMB), "--memory-mb", "300", "--json")
    assert done.returncode == 3, done.stderr
    result = json.loads(done.stdout)
    assert result["exit"] == "memory_limit"
    assert "memory limit: the program ran out of its 300 MB of memory (--memory-mb)" in result["error"]
    assert took < 30


@pytest.mark.e2e
def test_ctrl_c_stops_the_program_and_exits_130_with_the_report(tmp_path):
    cli = subprocess.Popen(
        [
            sys.executable,
            "-m",
            "openbricks_server.cli",
            "sim",
            "run",
            str(write(tmp_path, "s.py", SLEEPY_LOOP)),
        ],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        start_new_session=True,
    )
    try:
        assert cli.stdout.readline() == "started\n"  # the program runs in the child now
        cli.send_signal(signal.SIGINT)
        out, err = cli.communicate(timeout=30)
    finally:
        if cli.poll() is None:
            os.killpg(cli.pid, signal.SIGKILL)
    assert cli.returncode == 130, err
    assert "[stopped]" in err and "Traceback" not in err


@pytest.mark.e2e
def test_a_busy_loop_that_swallows_every_interrupt_is_killed_at_its_cpu_limit(tmp_path):
    program = write(tmp_path, "stubborn.py", STUBBORN_LOOP)
    done, took = sim_run(program, "--wall-limit", "0", "--cpu-limit", "2")
    assert done.returncode == 3, done.stderr
    assert "CPU-time limit: the run's process used its 2 s of processor time (--cpu-limit)" in done.stderr
    assert "[cpu_limit]" in done.stderr
    assert took < 60


@pytest.mark.e2e
def test_a_busy_loop_that_swallows_every_interrupt_is_killed_after_its_wall_limit(tmp_path):
    program = write(tmp_path, "stubborn.py", STUBBORN_LOOP)
    done, took = sim_run(program, "--wall-limit", "1", "--cpu-limit", "0")
    assert done.returncode == 3, done.stderr
    assert "wall-clock limit: the program was still running 1 s (--wall-limit) plus 10 s" in done.stderr
    assert 11 <= took < 40


@pytest.mark.e2e
@pytest.mark.parametrize(
    ("source", "message"),
    [
        ("import subprocess\n", "ImportError: no module named 'subprocess'"),
        ("import io\nprint(io.open('/etc/passwd').read())\n", "OSError: [Errno 2] ENOENT"),
        ("print(open('../../../etc/passwd').read())\n", "OSError: [Errno 2] ENOENT"),
        ("import os\nos.fork()\n", "AttributeError: module 'os' has no attribute 'fork'"),
        # Past the hub's Python to the host's os module: the kernel still refuses a new process.
        (HOST_OS + "['fork']()\n", "OSError: [Errno 1] Operation not permitted"),
        (
            HOST_OS + "['system']('touch /tmp/openbricks-escaped')\n",
            "",  # os.system's fork fails: it returns -1, nothing ran
        ),
    ],
    ids=[
        "import-subprocess",
        "io-open-etc-passwd",
        "open-dotdot",
        "os-fork",
        "escaped-fork",
        "escaped-system",
    ],
)
def test_a_program_reaches_only_the_hub(tmp_path, source, message):
    marker = "/tmp/openbricks-escaped"
    if os.path.exists(marker):
        os.remove(marker)
    done, took = sim_run(write(tmp_path, "reach.py", source))
    assert message in done.stderr
    assert "sim/run.py" not in done.stderr  # the traceback shows the program's frames only
    assert not os.path.exists(marker)
    assert took < 60


def test_a_negative_seed_is_a_usage_error_not_a_traceback(tmp_path):
    done, _ = sim_run(write(tmp_path, "ok.py", "print(1)\n"), "--seed", "-3")
    assert done.returncode == 2
    assert "argument --seed: '-3': give a whole number from 0 up" in done.stderr
    assert "Traceback" not in done.stderr
