"""A warm process that forks contained children on request: sim jobs start without paying for imports.

A run's child spends most of its start-up importing (MuJoCo, numpy, the 3D view's server, the
runtime's shim) before the program's first line. A fork server pays that once: it imports them,
freezes what it built out of the collector's reach (so children share its pages), and then forks one
child per request. Each child is a fork_child() (forked.py) running one of TARGETS, which fences
itself in first thing (limits.contain, the hub's imports) exactly as a spawned child does: the
fence is the child's own doing, however it was made.

    with ForkServer() as server:                    # spawns the server; it warms up meanwhile
        child = server.start("run", args, stdin=fd, stdout=fd, stderr=fd, pass_fds=(result_fd,))
        child.wait(timeout=60)                      # subprocess.Popen's poll/wait/send_signal/kill

The protocol, for the daemon's asyncio side too: requests travel on a datagram socket pair, one
message each (JSON: target, args, cwd) carrying its descriptors (a stream socket for the reply, then
the child's stdin, stdout, stderr and any it keeps); the reply stream says `{"pid": N}` once the
child is forked and `{"exit": STATUS}` when the server has reaped it (negative: the signal that
ended it). Closing the server's stdin (or ending the process that holds it) ends the server once its
children have ended. A server shared by a user's `sim run`s (shared_server.py) takes the same requests
on a socket it publishes at a path, with the requester's environment in them.
"""

from __future__ import annotations

import functools
import gc
import importlib
import json
import os
import select
import signal
import socket
import subprocess
import sys
import threading
import time

from .forked import ForkServerError, can_fork, fork_child

# What a child may run: name -> "module:function(args) -> exit status".
TARGETS = {
    "run": "openbricks_sim.run_process:child_main",  # `openbricks sim run`'s child (a sweep's seed)
    "console_job": "openbricks_sim.console_job:main",  # the console's watched sim run
}
# Imported before the first fork: what every target would otherwise import for itself.
WARM_IMPORTS = (
    "mujoco",
    "openbricks_sim.physics",
    "openbricks_sim.robot",
    "openbricks_sim.sensors.rig",
    "openbricks_sim.worlds",
    "openbricks_sim.run",
    "openbricks_sim.run_process",
    "openbricks_sim.console_job",
    "openbricks_sim.viewer",
    "openbricks_sim.viewer.session",
)
REQUEST_MAX_BYTES = 256 * 1024
MAX_FDS = 8
START_TIMEOUT_S = 60.0  # the server's own imports on a busy machine, before it forks the first child
PUBLISHED_CHECK_S = 1.0  # how often a published server looks whether it is idle or replaced


# --- the server -------------------------------------------------------------------------------------


def serve(control_fd: int, published=None) -> int:
    """The server's main loop: fork a child per request, report each one's end.

    A private server (ForkServer) ends when its stdin closes. A published one (shared_server.py:
    `published` says whether its socket is still the one at its path) ends when it has been idle for
    shared_server.IDLE_S or its socket was taken away, once its children have ended."""
    # Interrupts are for the children (whoever asked for them forwards them).
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    control = socket.socket(fileno=control_fd)
    wake_read, wake_write = os.pipe()
    os.set_blocking(wake_read, False)
    os.set_blocking(wake_write, False)
    signal.set_wakeup_fd(wake_write)
    signal.signal(signal.SIGCHLD, lambda *_: None)  # only to wake the loop
    children: dict[int, socket.socket] = {}
    accepting = True
    watched = [control, wake_read] if published is not None else [control, 0, wake_read]
    while accepting or children:
        timeout = None if published is None else PUBLISHED_CHECK_S
        readable, _, _ = select.select(watched if accepting else [wake_read], [], [], timeout)
        if 0 in readable and not os.read(0, 4096):  # stdin closed: whoever started us is done
            accepting = False
        elif control in readable and not _take_request(control, children):
            accepting = published is not None  # a private server's requester closed its end
        if wake_read in readable:
            try:
                os.read(wake_read, 4096)
            except BlockingIOError:
                pass
        _reap(children)
        if accepting and published is not None and not published(busy=bool(children) or bool(readable)):
            # No new requester can reach us now; what was sent before that is still served.
            while select.select([control], [], [], 0)[0] and _take_request(control, children):
                pass
            accepting = False
    return 0


def _take_request(control: socket.socket, children: dict[int, socket.socket]) -> bool:
    """Receive one request and fork its child; False if the socket gave nothing (its peer closed)."""
    try:
        message, fds, _flags, _address = socket.recv_fds(control, REQUEST_MAX_BYTES, MAX_FDS)
    except OSError:
        message, fds = b"", []
    if not message:
        return False
    pid, reply = _fork_request(message, fds)
    if pid is not None:
        children[pid] = reply
    return True


def warm_up() -> None:
    """Import what every target would import for itself, show a robot once, and freeze the result out
    of the collector's reach (so children share the pages)."""
    for name in WARM_IMPORTS:
        try:
            importlib.import_module(name)
        except Exception:  # noqa: BLE001 - a MuJoCo that does not load, a broken world file: each
            pass  # child meets it again and reports it as its result
    _warm_up()
    gc.collect()
    gc.freeze()


def _warm_up() -> None:
    """Show a robot in a 3D view once and close it: what the first view of a process pays (viser's
    and rich's own lazy imports, mjviser's mesh and type-hint caches) is then paid here, not by each
    child. The view's threads end before the first fork, which needs this process alone on one."""
    try:
        from .simulation import Simulation
        from .viewer import SimViewer

        simulation = Simulation()
        try:
            with SimViewer(port=0, controls=False, record=True) as viewer:
                viewer.attach(simulation)
                viewer.detach(None)
        finally:
            simulation.close()
    except Exception:  # noqa: BLE001 - a warm-up that fails leaves the children to pay for themselves
        pass
    deadline = time.monotonic() + 10
    while threading.active_count() > 1 and time.monotonic() < deadline:
        time.sleep(0.01)


def _fork_request(message: bytes, fds: list[int]):
    """Fork the child a request asks for; (its pid, the reply socket), or (None, None) if refused."""
    reply = socket.socket(fileno=fds[0]) if fds else None
    passed = fds[1:]
    try:
        request = json.loads(message)
        target = TARGETS[request["target"]]
        stdin, stdout, stderr, *keep = passed
        if not can_fork():  # a thread of the warm-up that never ended: a fork could deadlock
            raise ForkServerError(f"the fork server runs {threading.active_count()} threads")
        environment = request.get("env")
        if environment is not None and not all(isinstance(v, str) for v in dict(environment).values()):
            raise TypeError("env values must be strings")
        pid = fork_child(
            functools.partial(_run_target, target, list(request["args"]), request.get("cwd"), environment),
            stdin=stdin,
            stdout=stdout,
            stderr=stderr,
            extra_fds=tuple(keep),
        ).pid
    except (ValueError, KeyError, TypeError, ForkServerError) as exc:
        if reply is not None:
            _send(reply, {"error": f"bad request: {exc}"})
            reply.close()
        return None, None
    finally:
        for fd in passed:
            os.close(fd)
    _send(reply, {"pid": pid})
    return pid, reply


def _run_target(target: str, args: list[str], cwd: str | None, environment: dict | None = None):
    """In the child: the requester's working folder and (a shared server's) environment, then the target."""
    module_name, function = target.split(":")
    if cwd is not None:
        os.chdir(cwd)
    if environment is not None:
        os.environ.clear()
        os.environ.update(environment)
        tempfile = sys.modules.get("tempfile")
        if tempfile is not None:
            tempfile.tempdir = None  # found again from this TMPDIR, not the server's
    return getattr(importlib.import_module(module_name), function)(args)


def _reap(children: dict[int, socket.socket]) -> None:
    while children:
        try:
            pid, status = os.waitpid(-1, os.WNOHANG)
        except ChildProcessError:
            return
        if pid == 0:
            return
        reply = children.pop(pid, None)
        if reply is not None:
            _send(reply, {"exit": os.waitstatus_to_exitcode(status)})
            reply.close()


def _send(reply: socket.socket, message: dict) -> None:
    try:
        reply.sendall((json.dumps(message) + "\n").encode())
    except OSError:  # whoever asked is gone; the child runs on within its own limits
        pass


# --- the client -------------------------------------------------------------------------------------


class ForkServerClient:
    """Requests to a fork server over `control`, its datagram socket (thread-safe)."""

    def __init__(self, control: socket.socket, environment: dict | None = None, cwd: str | None = None):
        self.control = control
        # A shared server's children take on the requester's environment and folder (a request's own
        # cwd wins); a private server's have its own, which are this process's.
        self.environment = environment
        self.cwd = cwd
        self._lock = threading.Lock()

    def _check_alive(self) -> None:
        pass

    def request(self, target: str, args: list[str], fds: list[int], cwd: str | None = None) -> socket.socket:
        """Send one request (fds: stdin, stdout, stderr, then those the child keeps, which are its 3, 4,
        ... there); the reply socket."""
        if target not in TARGETS:
            raise ForkServerError(f"unknown target {target!r}: one of {', '.join(TARGETS)}")
        self._check_alive()
        ours, theirs = socket.socketpair()
        request = {"target": target, "args": args, "cwd": cwd if cwd is not None else self.cwd}
        if self.environment is not None:
            request["env"] = self.environment
        message = json.dumps(request).encode()
        try:
            with self._lock:
                socket.send_fds(self.control, [message], [theirs.fileno(), *fds])
        except OSError as exc:
            ours.close()
            raise ForkServerError(f"the fork server did not take the request: {exc}") from None
        finally:
            theirs.close()
        return ours

    def start(
        self,
        target: str,
        args: list[str],
        *,
        stdin: int | None = None,
        stdout: int | None = None,
        stderr: int | None = None,
        pass_fds: tuple[int, ...] = (),
        cwd: str | None = None,
    ) -> WarmChild:
        """A child running TARGETS[target](args); None for a stream gives it this process's own;
        pass_fds are the child's 3, 4, ... (args name them so)."""
        stdio = [fd if fd is not None else default for fd, default in ((stdin, 0), (stdout, 1), (stderr, 2))]
        reply = self.request(target, args, [*stdio, *pass_fds], cwd)
        child = WarmChild(reply)
        child.wait_for_pid(START_TIMEOUT_S)
        return child

    def close(self) -> None:
        self.control.close()

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()
        return False


class ForkServer(ForkServerClient):
    """A private fork server process (it ends with this process) and the requests sent to it."""

    def __init__(self):
        ours, theirs = socket.socketpair(socket.AF_UNIX, socket.SOCK_DGRAM)
        try:
            self.process = subprocess.Popen(
                [sys.executable, "-m", "openbricks_sim.fork_server", str(theirs.fileno())],
                stdin=subprocess.PIPE,  # its end closing (we are gone) ends the server
                pass_fds=(theirs.fileno(),),
                start_new_session=True,
            )
        finally:
            theirs.close()
        super().__init__(ours)

    def _check_alive(self) -> None:
        if self.process.poll() is not None:
            raise ForkServerError(f"the fork server has ended (status {self.process.returncode})")

    def close(self) -> None:
        """No more requests: the server ends once its children have (it is killed if it does not)."""
        self.control.close()
        self.process.stdin.close()
        try:
            self.process.wait(timeout=START_TIMEOUT_S)
        except subprocess.TimeoutExpired:
            self.process.kill()
            self.process.wait()


class WarmChild:
    """A forked child as its requester sees it: subprocess.Popen's pid, poll, wait, send_signal, kill."""

    def __init__(self, reply: socket.socket):
        self._reply = reply
        self._buffer = b""
        self.pid: int | None = None
        self.returncode: int | None = None

    def wait_for_pid(self, timeout_s: float) -> int:
        message = self._next(timeout_s)
        if message is None or "pid" not in message:
            why = message.get("error") if message else "no answer"
            raise ForkServerError(f"the fork server did not start the child: {why}")
        self.pid = int(message["pid"])
        return self.pid

    def poll(self) -> int | None:
        if self.returncode is None:
            self._read_exit(0)
        return self.returncode

    def wait(self, timeout: float | None = None) -> int:
        if self.returncode is None and not self._read_exit(timeout):
            raise subprocess.TimeoutExpired(f"child {self.pid}", timeout)
        return self.returncode

    def send_signal(self, signum: int) -> None:
        if self.returncode is None and self.pid is not None:
            try:
                os.kill(self.pid, signum)
            except ProcessLookupError:
                pass

    def kill(self) -> None:
        self.send_signal(signal.SIGKILL)

    def _read_exit(self, timeout: float | None) -> bool:
        message = self._next(timeout)
        if message is None:
            return False
        # The server reports the status; a server that went away first leaves the child's end unknown.
        self.returncode = int(message.get("exit", -signal.SIGKILL))
        self._reply.close()
        return True

    def _next(self, timeout: float | None) -> dict | None:
        """The next reply line, or None if none came within timeout (EOF reads as {})."""
        while b"\n" not in self._buffer:
            ready, _, _ = select.select([self._reply], [], [], timeout)
            if not ready:
                return None
            chunk = self._reply.recv(4096)
            if not chunk:
                return {}
            self._buffer += chunk
        line, self._buffer = self._buffer.split(b"\n", 1)
        return json.loads(line)


if __name__ == "__main__":
    if sys.argv[1] == "--publish":  # a shared server (shared_server.py): warm up, then publish the socket
        from .shared_server import publish_and_serve

        sys.exit(publish_and_serve(sys.argv[2]))
    warm_up()
    sys.exit(serve(int(sys.argv[1])))
