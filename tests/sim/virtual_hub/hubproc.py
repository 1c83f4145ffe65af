"""A virtual hub process for end-to-end tests, and a host that talks to it byte by byte.

Every wait has a timeout, and the process is stopped (SIGTERM, then SIGKILL) whatever the test did.
"""

import json
import os
import signal
import socket
import subprocess
import sys
import time

import serial

START_TIMEOUT_S = 60
STOP_TIMEOUT_S = 15


def child_env():
    """The child imports the same builds of the native extensions as this test process."""
    import openbricks_mjcontrol

    import openbricks_native

    env = dict(os.environ)
    paths = {os.path.dirname(openbricks_native.__file__), os.path.dirname(openbricks_mjcontrol.__file__)}
    env["PYTHONPATH"] = os.pathsep.join([*paths, env.get("PYTHONPATH", "")])
    return env


class HubProcess:
    """`python -m openbricks_sim.virtual_hub --pty` in a directory of its own."""

    def __init__(self, directory, name="RobotA", *extra):
        self.directory = str(directory)
        self.name = name
        os.makedirs(self.directory, exist_ok=True)
        self.stderr_path = os.path.join(self.directory, "..", f"{name}-stderr.txt")
        self._stderr = open(self.stderr_path, "wb")  # noqa: SIM115 - closed in stop()
        self.proc = subprocess.Popen(
            [
                sys.executable,
                "-m",
                "openbricks_sim.virtual_hub",
                "--name",
                name,
                "--pty",
                "--dir",
                self.directory,
                *extra,
            ],
            stdout=subprocess.PIPE,
            stderr=self._stderr,
            env=child_env(),
            cwd=os.path.dirname(self.directory),
        )
        self.pty = self._line()
        control = self._line()
        assert control.startswith("control "), control
        self.control_path = control[len("control ") :]

    def _line(self):
        deadline = time.monotonic() + START_TIMEOUT_S
        line = b""
        while not line.endswith(b"\n"):
            if time.monotonic() > deadline or self.proc.poll() is not None:
                self.stop()
                raise AssertionError(f"the virtual hub did not start: {self.stderr()}")
            line += os.read(self.proc.stdout.fileno(), 1)
        return line.decode().strip()

    def stderr(self):
        with open(self.stderr_path, "rb") as f:
            return f.read().decode(errors="replace")

    def control(self, op, timeout_s=5):
        with socket.socket(socket.AF_UNIX, socket.SOCK_STREAM) as sock:
            sock.settimeout(timeout_s)
            sock.connect(self.control_path)
            sock.sendall(json.dumps({"op": op}).encode() + b"\n")
            reply = b""
            while not reply.endswith(b"\n"):
                chunk = sock.recv(4096)
                if not chunk:
                    break
                reply += chunk
        return json.loads(reply)

    def mpremote(self, *args, timeout_s=60):
        return subprocess.run(
            [sys.executable, "-m", "mpremote", "connect", self.pty, *args],
            capture_output=True,
            timeout=timeout_s,
            env=child_env(),
            cwd=os.path.dirname(self.directory),
        )

    def stop(self):
        if self.proc.poll() is None:
            self.proc.send_signal(signal.SIGTERM)
            try:
                self.proc.wait(STOP_TIMEOUT_S)
            except subprocess.TimeoutExpired:
                self.proc.kill()
                self.proc.wait(STOP_TIMEOUT_S)
        self.proc.stdout.close()
        self._stderr.close()
        return self.proc.returncode


class Host:
    """A raw byte-level host on the hub's pty (what the openbricks serial link does)."""

    def __init__(self, pty_path):
        self.port = serial.Serial(pty_path, 115200, timeout=0.05)
        self.seen = bytearray()

    def close(self):
        self.port.close()

    def write(self, data):
        self.port.write(data)

    def read_until(self, ending, timeout_s=20):
        data = bytearray()
        deadline = time.monotonic() + timeout_s
        while not data.endswith(ending):
            if time.monotonic() > deadline:
                raise AssertionError(f"no {ending!r} within {timeout_s} s; got {bytes(data)!r}")
            data.extend(self.port.read(1))
        self.seen.extend(data)
        return bytes(data)

    def read_exactly(self, n, timeout_s=20):
        data = bytearray()
        deadline = time.monotonic() + timeout_s
        while len(data) < n:
            if time.monotonic() > deadline:
                raise AssertionError(f"{len(data)} of {n} bytes within {timeout_s} s: {bytes(data)!r}")
            data.extend(self.port.read(n - len(data)))
        return bytes(data)

    def enter_raw(self):
        """Interrupt whatever runs (main.py's launcher at boot) and get to the raw REPL prompt."""
        self.write(b"\r\x03")
        time.sleep(0.2)
        self.port.reset_input_buffer()
        self.write(b"\r\x01")
        self.read_until(b"raw REPL; CTRL-B to exit\r\n>")

    def exec_raw(self, source, timeout_s=30):
        """Run source in the raw REPL; returns (stdout, stderr) as text."""
        self.write(source.encode() + b"\x04")
        assert self.read_exactly(2) == b"OK"
        out = self.read_until(b"\x04", timeout_s)[:-1]
        err = self.read_until(b"\x04", timeout_s)[:-1]
        assert self.read_exactly(1) == b">"
        return out.decode(), err.decode()

    def call(self, expression, timeout_s=30):
        """A host call (openbricks.host_calls) and its one result line, as a dict."""
        out, err = self.exec_raw(f"import openbricks.host_calls as h\n{expression}", timeout_s)
        assert not err, err
        return result_of(out)


def result_of(output):
    marker = "@openbricks:- result "  # an untagged call's result frame
    lines = [line for line in output.splitlines() if line.startswith(marker)]
    assert len(lines) == 1, output
    return json.loads(lines[0][len(marker) :])
