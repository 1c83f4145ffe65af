"""The hub's console streams: sys.stdout/sys.stderr/sys.stdin of code running on the virtual hub.

Output is MicroPython's cooked stdout: every "\\n" goes out as "\\r\\n", straight to the link with no
buffering (a hub's print reaches the host as it happens). `sys.stdout.buffer` writes raw bytes.
Input is the bytes the host sent while the code runs (the REPL keeps them for it, see
ReplProtocol.stdin); reads block until some arrive, and a Ctrl-C ends the wait.
"""

import io
import threading

from .repl import cooked


class ConsoleOut(io.TextIOBase):
    """Text to the host; `send(bytes)` is the hub's (thread-safe) link writer."""

    def __init__(self, send):
        self._send = send
        self.buffer = _RawOut(send)

    def writable(self):
        return True

    def write(self, text):
        if not isinstance(text, str):
            raise TypeError(f"write() argument must be str, not {type(text).__name__}")
        if text:
            self._send(cooked(text))
        return len(text)

    def flush(self):
        pass

    def isatty(self):
        return False


class _RawOut(io.RawIOBase):
    def __init__(self, send):
        self._send = send

    def writable(self):
        return True

    def write(self, data, n=None):
        """MicroPython's stream write(buf[, n]): the first n bytes of buf."""
        data = bytes(data) if n is None else bytes(memoryview(data)[:n])
        self._send(data)
        return len(data)


class ConsoleIn(io.TextIOBase):
    """The running code's stdin. `take(n)` returns up to n waiting bytes (b"" if none); call
    `notify()` whenever new bytes may have arrived or an interrupt is due."""

    def __init__(self, take, interrupted, peek=None):
        self._take = take
        self._peek = peek or (lambda: False)  # are bytes waiting?
        self._interrupted = interrupted  # an Event set while a Ctrl-C is being delivered
        self._ready = threading.Condition()
        self.buffer = _RawIn(self)

    console_input = True  # what the hub's select.poll() waits on

    def notify(self):
        with self._ready:
            self._ready.notify_all()

    def wait_readable(self, timeout_s=None):
        """True once bytes from the host wait to be read (False after timeout_s without any)."""
        import time

        deadline = None if timeout_s is None else time.monotonic() + timeout_s
        with self._ready:
            while not self._peek():
                remaining = 0.5 if deadline is None else min(0.5, deadline - time.monotonic())
                if remaining <= 0:
                    return False
                self._ready.wait(remaining)
            return True

    def readable(self):
        return True

    def read_bytes(self, n):
        """At least one and at most n bytes, waiting for the host."""
        with self._ready:
            while True:
                data = self._take(n)
                if data:
                    return data
                if self._interrupted.is_set():
                    # The KeyboardInterrupt is being raised in this thread: let it arrive.
                    self._ready.wait(0.05)
                    continue
                self._ready.wait(0.5)

    def read(self, size=-1):
        if size is None or size < 0:
            raise OSError("the console has no end: read(n) with a count, or readline()")
        chars = []
        pending = b""
        while len(chars) < size:
            pending += self.read_bytes(1)
            try:
                chars.append(pending.decode("utf-8"))
                pending = b""
            except UnicodeDecodeError:
                if len(pending) >= 4:
                    chars.append(pending.decode("utf-8", "replace"))
                    pending = b""
        return "".join(chars)

    def readline(self, size=-1):
        line = []
        while size is None or size < 0 or len(line) < size:
            char = self.read(1)
            if char in ("\r", "\n"):
                line.append("\n")
                break
            line.append(char)
        return "".join(line)


class _RawIn(io.RawIOBase):
    console_input = True

    def __init__(self, console):
        self._console = console

    def readable(self):
        return True

    def readinto(self, buffer, n=None):
        """MicroPython's readinto(buf[, n]): at most n bytes (at least one, waiting for the host)."""
        view = memoryview(buffer).cast("B")
        data = self._console.read_bytes(len(view) if n is None else min(n, len(view)))
        view[: len(data)] = data
        return len(data)


def make_input(stdin, stdout):
    """input() as MicroPython's REPL readline does it on a serial console: echo, backspace, Enter."""

    def hub_input(prompt=""):
        stdout.write(str(prompt))
        line = []
        while True:
            char = stdin.read(1)
            if char in ("\r", "\n"):
                stdout.write("\n")
                return "".join(line)
            if char in ("\x08", "\x7f"):
                if line:
                    line.pop()
                    stdout.buffer.write(b"\x08 \x08")
                continue
            if char == "\x04" and not line:
                raise EOFError
            if char >= " ":
                line.append(char)
                stdout.write(char)

    return hub_input
