"""The byte streams a virtual hub talks over: a pseudo-terminal, or the process's stdin/stdout.

A pty looks like a hub's USB serial port to a host (`mpremote connect /dev/pts/N`, pyserial, the
openbricks serial link). The hub keeps its own handle on the terminal side open, so hosts can
connect and disconnect as often as they like; with nobody reading, output is discarded after a
short wait, as a USB CDC port with no host discards it, instead of stalling the hub.

Stdio serves a parent process that pipes the bytes itself. The process's real stdout becomes the
link, and file descriptor 1 is pointed at stderr, so stray prints from libraries can't corrupt it.
"""

import errno
import os
import select
import time
import tty

STALLED_WRITE_S = 1.0  # a pty nobody reads for this long is treated as disconnected


class PtyPort:
    """The hub's end of a pseudo-terminal; `path` is the end a host opens."""

    def __init__(self):
        self._master, self._slave = os.openpty()
        tty.setraw(self._slave)  # no echo, no CR/LF translation: bytes pass as on a serial port
        self.path = os.ttyname(self._slave)
        os.set_blocking(self._master, False)
        self._dropping = False
        self._closed = False

    def read(self, max_bytes=4096):
        """Block until bytes arrive; b"" once the port is closed."""
        while not self._closed:
            try:
                ready, _, _ = select.select([self._master], [], [], 0.5)
            except (OSError, ValueError):
                return b""
            if not ready:
                continue
            try:
                data = os.read(self._master, max_bytes)
            except BlockingIOError:
                continue
            except OSError as exc:
                if exc.errno == errno.EIO:  # no terminal side open (cannot happen while we hold one)
                    time.sleep(0.05)
                    continue
                return b""
            if data:
                return data
        return b""

    def write(self, data):
        view = memoryview(bytes(data))
        deadline = None
        while view and not self._closed:
            try:
                sent = os.write(self._master, view)
                view = view[sent:]
                self._dropping = False
                continue
            except BlockingIOError:
                pass
            if self._dropping:
                return  # nobody has read for a while: discard, as USB CDC without a host does
            now = time.monotonic()
            deadline = deadline or now + STALLED_WRITE_S
            if now >= deadline:
                self._dropping = True
                return
            select.select([], [self._master], [], deadline - now)

    def close(self):
        self._closed = True
        for fd in (self._master, self._slave):
            try:
                os.close(fd)
            except OSError:
                pass


class StdioPort:
    """The hub's link over this process's stdin and stdout."""

    def __init__(self):
        self._in = os.dup(0)
        self._out = os.dup(1)
        os.dup2(2, 1)  # anything else writing to fd 1 now lands on stderr
        self.path = None

    def read(self, max_bytes=4096):
        try:
            return os.read(self._in, max_bytes)
        except OSError:
            return b""

    def write(self, data):
        view = memoryview(bytes(data))
        while view:
            try:
                view = view[os.write(self._out, view) :]
            except BrokenPipeError:
                return

    def close(self):
        for fd in (self._in, self._out):
            try:
                os.close(fd)
            except OSError:
                pass
