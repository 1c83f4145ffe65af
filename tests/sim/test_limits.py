"""The OS layer of the fence (limits.contain): what holds even for code that got past the in-process
layers. Each case runs in a process of its own, which is fenced for good."""

import json
import subprocess
import sys

from openbricks_sim.limits import MIN_WALL_S, default_cpu_s, default_wall_s

PROBE = """\
import json, os, resource, subprocess, sys, threading
from openbricks_sim.limits import contain

contain(memory_mb=300, cpu_s=30, file_mb=1)
seen = {}

def attempt(name, action):
    try:
        action()
        seen[name] = "allowed"
    except (OSError, MemoryError, ValueError) as exc:
        seen[name] = type(exc).__name__ + ": " + str(exc)

attempt("fork", os.fork)
attempt("subprocess", lambda: subprocess.run(["true"]))
attempt("exec", lambda: os.execv("/bin/true", ["true"]))
attempt("memory", lambda: bytearray(400 * 1024 * 1024))
attempt("big file", lambda: open(sys.argv[1], "wb").write(b"x" * 2 * 1024 * 1024))
attempt("raise memory", lambda: resource.setrlimit(resource.RLIMIT_AS, (2**34, 2**34)))
thread = threading.Thread(target=lambda: seen.update(thread="ran"))
thread.start()
thread.join()
seen["no_new_privs"] = [l for l in open("/proc/self/status") if l.startswith("NoNewPrivs")][0].split()[1]
print(json.dumps(seen))
"""


def test_a_fenced_process_cannot_start_processes_or_outgrow_its_limits_but_runs_threads(tmp_path):
    done = subprocess.run(
        [sys.executable, "-c", PROBE, str(tmp_path / "big.bin")],
        capture_output=True,
        text=True,
        timeout=60,
    )
    assert done.returncode == 0, done.stderr
    seen = json.loads(done.stdout)
    assert seen["fork"] == "PermissionError: [Errno 1] Operation not permitted"
    assert seen["subprocess"].startswith("PermissionError: [Errno 1]")
    assert seen["exec"].startswith("PermissionError: [Errno 1]")
    assert seen["memory"] == "MemoryError: "
    assert seen["big file"] == "OSError: [Errno 27] File too large"
    assert seen["raise memory"].startswith("ValueError") or seen["raise memory"].startswith("PermissionError")
    assert seen["thread"] == "ran" and seen["no_new_privs"] == "1"


def test_the_default_wall_limit_follows_the_simulated_duration_and_the_pace():
    assert default_wall_s(60_000) == 60.0  # unpaced runs go many times faster than real time
    assert default_wall_s(60_000, speed=1.0) == 120.0  # paced: twice the real time it needs
    assert default_wall_s(60_000, speed=4.0) == 30.0
    assert default_wall_s(1_000) == MIN_WALL_S
    assert default_cpu_s(60.0) == 65 and default_cpu_s(0) is None
