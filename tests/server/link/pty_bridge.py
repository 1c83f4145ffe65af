"""A real virtual hub on the emulated radio: the peripheral's hub side is a virtual hub process's pty.

`FakeRadio.add_hub(PtyHubBridge(name, pty))` puts a hub on the air whose REPL, host calls, launcher
and run logs are the real runtime's (the same process `openbricks` talks to over a pty), while the
radio in between is the emulation (MTU, connection events, drops). Only the radio is pretend.
"""

from __future__ import annotations

import asyncio
import os
import time
import tty
from collections.abc import Callable

WRITE_TIMEOUT_S = 5.0


class PtyHubBridge:
    def __init__(self, name: str, pty: str):
        self.name = name
        self.pty = pty
        self._fd: int | None = None
        self._send: Callable[[bytes], None] = lambda data: None
        self._loop: asyncio.AbstractEventLoop | None = None

    def attach(self, send: Callable[[bytes], None], loop: asyncio.AbstractEventLoop) -> None:
        """Where the hub's output goes (on `loop`'s thread); opens the pty on first use."""
        self._send = send
        if self._fd is None:
            self._fd = os.open(self.pty, os.O_RDWR | os.O_NOCTTY | os.O_NONBLOCK)
            tty.setraw(self._fd)
        if self._loop is not loop:
            if self._loop is not None:
                self._loop.remove_reader(self._fd)
            self._loop = loop
            loop.add_reader(self._fd, self._readable)

    def _readable(self) -> None:
        try:
            data = os.read(self._fd, 65536)
        except BlockingIOError:
            return
        except OSError:
            self._loop.remove_reader(self._fd)  # the hub process is gone
            return
        if data:
            self._send(data)

    def feed(self, data: bytes) -> None:
        """Bytes from the host, in order (on the loop's thread)."""
        view = memoryview(data)
        deadline = time.monotonic() + WRITE_TIMEOUT_S
        while view:
            try:
                view = view[os.write(self._fd, view) :]
            except BlockingIOError:
                if time.monotonic() > deadline:
                    raise TimeoutError(f"virtual hub {self.name} stopped reading its pty") from None
                time.sleep(0.001)

    def close(self) -> None:
        if self._fd is not None:
            if self._loop is not None:
                self._loop.remove_reader(self._fd)
            os.close(self._fd)
            self._fd = None
