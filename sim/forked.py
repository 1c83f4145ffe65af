"""A child process made by fork() rather than by starting a new interpreter.

A new interpreter costs its own start-up (the interpreter, site, every import again) before the
program's first line; a fork starts from what this process has already imported. So a process that
runs user code forks a child for it when it safely can, and the child fences itself in exactly as a
spawned one does (run.py and console_job.py call limits.contain() first thing): the fence is the
child's own doing, whichever way it was made.

Forking is safe only from a process with one thread (a lock another thread holds would stay held in
the child forever) and only where the OS has fork(); `can_fork()` says so, and the callers spawn a
new interpreter otherwise.
"""

from __future__ import annotations

import fcntl
import io
import os
import select
import signal
import subprocess
import sys
import threading
import time
import traceback
from collections.abc import Callable

# The dispositions a fresh interpreter starts with: whatever the parent installed (a CLI forwarding
# Ctrl-C, a server's shutdown handler) must not run in the child.
_FRESH_SIGNALS = {
    signal.SIGTERM: signal.SIG_DFL,
    signal.SIGHUP: signal.SIG_DFL,
    signal.SIGCHLD: signal.SIG_DFL,
}
_HIGH_FD = 100  # where descriptors wait while the child's 0, 1, 2, 3, ... are laid out


class ForkServerError(RuntimeError):
    """A fork server (fork_server.py) is gone or refused a request: its requester starts the child cold."""


def can_fork() -> bool:
    """Whether fork() is safe here: the OS has it and this process runs one thread."""
    return hasattr(os, "fork") and threading.active_count() == 1


class ForkedChild:
    """The parent's handle on a forked child: subprocess.Popen's poll/wait/send_signal/kill."""

    def __init__(self, pid: int):
        self.pid = pid
        self.returncode: int | None = None
        self._pidfd = _pidfd(pid)

    def poll(self) -> int | None:
        if self.returncode is None:
            pid, status = os.waitpid(self.pid, os.WNOHANG)
            if pid == self.pid:
                self._reaped(status)
        return self.returncode

    def wait(self, timeout: float | None = None) -> int:
        """The exit status (negative: the signal that ended it); TimeoutExpired after timeout seconds."""
        if timeout is None:
            if self.returncode is None:
                self._reaped(os.waitpid(self.pid, 0)[1])
            return self.returncode
        deadline = time.monotonic() + timeout
        pause_s = 0.001
        while self.poll() is None:
            left = deadline - time.monotonic()
            if left <= 0:
                raise subprocess.TimeoutExpired(f"child {self.pid}", timeout)
            if self._pidfd is not None:
                select.select([self._pidfd], [], [], left)  # readable when the child ends
            else:
                time.sleep(min(pause_s, left))
                pause_s = min(pause_s * 2, 0.05)
        return self.returncode

    def send_signal(self, signum: int) -> None:
        if self.returncode is None:
            try:
                os.kill(self.pid, signum)
            except ProcessLookupError:  # ended, not yet reaped
                pass

    def kill(self) -> None:
        self.send_signal(signal.SIGKILL)

    def _reaped(self, status: int) -> None:
        self.returncode = os.waitstatus_to_exitcode(status)
        if self._pidfd is not None:
            os.close(self._pidfd)
            self._pidfd = None


def _pidfd(pid: int) -> int | None:
    """A descriptor that becomes readable when `pid` ends (Linux 5.3 and later), else None."""
    try:
        return os.pidfd_open(pid)
    except (AttributeError, OSError):
        return None


def fork_child(
    main: Callable[[], int | None],
    *,
    stdin: int | None = None,
    stdout: int | None = None,
    stderr: int | None = None,
    extra_fds: tuple[int, ...] = (),
) -> ForkedChild:
    """Fork; the child runs main() in a session of its own and exits with its status, never returning.

    stdin/stdout/stderr: descriptors to put in the child's 0/1/2 (None keeps the parent's); extra_fds
    become the child's 3, 4, ... in order. Every other descriptor is closed in the child, as
    subprocess closes them for a spawned one: a child holds nothing of its parent's (a server's
    sockets, the other ends of its pipes)."""
    sys.stdout.flush()
    sys.stderr.flush()
    pid = os.fork()
    if pid:
        return ForkedChild(pid)
    status = 1
    try:
        os.setsid()
        signal.set_wakeup_fd(-1)
        # Out of the way first, so that moving one onto 3, 4, ... cannot overwrite another.
        moved = [
            fcntl.fcntl(fd, fcntl.F_DUPFD_CLOEXEC, _HIGH_FD)
            for fd in (stdin, stdout, stderr, *extra_fds)
            if fd is not None
        ]
        for target, fd in enumerate((stdin, stdout, stderr)):
            if fd is not None:
                os.dup2(moved.pop(0), target)
        for target, fd in enumerate(moved, start=3):
            os.dup2(fd, target)  # dup2 leaves the copy inheritable, as the child's own descriptor
        os.closerange(3 + len(extra_fds), _max_fd())
        # Python's streams onto the descriptors, as a new interpreter's are (the parent may have put
        # its own objects there: a test's capture, a console's wrapper).
        if stdout is not None:
            sys.stdout = _text_stream(1, sys.__stdout__)
        if stderr is not None:
            sys.stderr = _text_stream(2, sys.__stderr__)
        signal.signal(signal.SIGINT, signal.default_int_handler)
        for signum, disposition in _FRESH_SIGNALS.items():
            signal.signal(signum, disposition)
        status = _exit_status(main)
    finally:
        try:
            sys.stdout.flush()
            sys.stderr.flush()
        finally:
            os._exit(status)


def _max_fd() -> int:
    try:
        return os.sysconf("SC_OPEN_MAX")
    except (ValueError, OSError):
        return 65536


def _text_stream(fd: int, like):
    encoding = getattr(like, "encoding", None) or "utf-8"
    errors = getattr(like, "errors", None) or "strict"
    # stderr is line-buffered, as Python's own is since 3.9
    return io.TextIOWrapper(
        io.FileIO(fd, "w", closefd=False), encoding=encoding, errors=errors, line_buffering=fd == 2
    )


def _exit_status(main) -> int:
    """main()'s exit status as the interpreter would give it: SystemExit's code, 130 for an interrupt,
    1 with the traceback for anything else raised."""
    try:
        code = main()
    except SystemExit as exc:
        code = exc.code
    except KeyboardInterrupt:
        return 130
    except BaseException:  # noqa: BLE001 - as an interpreter would: printed, then exit 1
        traceback.print_exc()
        return 1
    if code is None:
        return 0
    if isinstance(code, int):
        return code
    print(code, file=sys.stderr)
    return 1
