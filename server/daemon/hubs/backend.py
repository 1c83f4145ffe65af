"""What the daemon needs of a hub, whatever carries it: a name, a stable address, and a fresh link.

BLE, USB-serial and virtual hubs differ only in how a link to them is made (and a virtual hub the
daemon started is a process it must stop), so that is all a backend says. The actor, the manager and
the routers never ask which kind they hold. A hub's stable id is its kind plus its address (BLE
address, serial port, virtual hub name), so a hub renamed over BLE keeps its id and its history.
"""

from __future__ import annotations

import asyncio
import ctypes
import os
import signal
import sys
from abc import ABC, abstractmethod
from typing import Any

from openbricks_server.daemon.hub_events import HubKind
from openbricks_server.link.base import Link
from openbricks_server.link.errors import LinkError, LinkTimeout

CONNECT_TIMEOUT_S = 20.0
VIRTUAL_START_TIMEOUT_S = 30.0
VIRTUAL_STOP_GRACE_S = 5.0
_PR_SET_PDEATHSIG = 1  # <linux/prctl.h>
_prctl = ctypes.CDLL(None, use_errno=True).prctl if sys.platform.startswith("linux") else None


def hub_id(kind: HubKind, address: str) -> str:
    return f"{kind}:{address}"


def port_slug(port: str) -> str:
    """A serial port as one URL path segment: /dev/ttyUSB0 -> ttyUSB0, /dev/pts/3 -> pts-3, COM5 -> COM5."""
    return port.removeprefix("/dev/").strip("/").replace("/", "-").replace("\\", "-") or port


class HubBackend(ABC):
    kind: HubKind

    def __init__(self, name: str, address: str):
        self.name = name
        self.address = address

    @property
    def hub_id(self) -> str:
        return hub_id(self.kind, self.address)

    @property
    def serial_port(self) -> str | None:
        """The serial port (or pty) the hub's link goes through, if any: a flash job on that port must
        take the hub's link away first."""
        return None

    @abstractmethod
    def make_link(self) -> Link:
        """A new, unconnected link to the hub."""

    async def close(self) -> None:  # noqa: B027 - most backends own nothing but the link
        """Release what the backend owns (a virtual hub process); the actor has closed its link."""


class SerialBackend(HubBackend):
    """A hub on a USB serial port (or a pty that behaves like one)."""

    kind: HubKind = "serial"

    def __init__(self, name: str, port: str):
        super().__init__(name, port)
        self.port = port

    @property
    def hub_id(self) -> str:
        return hub_id(self.kind, port_slug(self.port))  # the port's path would not fit in a URL segment

    @property
    def serial_port(self) -> str | None:
        return self.port

    def make_link(self) -> Link:
        from openbricks_server.link.serial_link import SerialLink

        return SerialLink(self.port, hub=self.name, connect_timeout_s=CONNECT_TIMEOUT_S)


class BleBackend(HubBackend):
    """A hub seen on a BLE scan; `client_backend` is bleak's (None: the OS's; tests: an emulated radio)."""

    kind: HubKind = "ble"

    def __init__(self, name: str, address: str, device: Any, *, client_backend: type | None = None):
        super().__init__(name, address)
        self.device = device
        self.client_backend = client_backend

    def make_link(self) -> Link:
        from openbricks_server.link.ble import BleLink

        return BleLink(
            self.name,
            device=self.device,
            client_backend=self.client_backend,
            connect_timeout_s=CONNECT_TIMEOUT_S,
        )


class VirtualBackend(HubBackend):
    """A virtual hub serving its REPL on a pty; `process` is set when the daemon started it (and stops it)."""

    kind: HubKind = "virtual"

    def __init__(self, name: str, pty: str, process: asyncio.subprocess.Process | None = None):
        super().__init__(name, name)
        self.pty = pty
        self.process = process
        self._drains: list[asyncio.Task] = []
        if process is not None:
            # Whatever the process still prints must be read, or a full pipe would stall the hub.
            self._drains = [asyncio.create_task(_drain(s)) for s in (process.stdout, process.stderr) if s]

    @property
    def serial_port(self) -> str | None:
        return self.pty

    def make_link(self) -> Link:
        from openbricks_server.link.serial_link import SerialLink

        return SerialLink(self.pty, hub=self.name, connect_timeout_s=CONNECT_TIMEOUT_S)

    async def close(self) -> None:
        process, self.process = self.process, None
        if process is not None and process.returncode is None:
            process.terminate()
            try:
                async with asyncio.timeout(VIRTUAL_STOP_GRACE_S):
                    await process.wait()
            except TimeoutError:
                process.kill()
                await process.wait()
        for task in self._drains:
            task.cancel()
        await asyncio.gather(*self._drains, return_exceptions=True)


async def _drain(stream: asyncio.StreamReader) -> None:
    while await stream.read(65536):
        pass


async def start_virtual_hub(
    name: str, *, hub_dir: str, world: str | None = None, data_dir: str | None = None
) -> VirtualBackend:
    """Start a virtual hub process on a pty (its first line names the pty) and return its backend."""
    from openbricks_server.link.virtual import virtual_hub_command

    command = virtual_hub_command(name, hub_dir=hub_dir, world=world, pty=True)
    env = dict(os.environ)
    if data_dir is not None:
        env["OPENBRICKS_DATA_DIR"] = str(data_dir)
    process = await asyncio.create_subprocess_exec(
        *command,
        stdin=asyncio.subprocess.DEVNULL,
        stdout=asyncio.subprocess.PIPE,
        stderr=asyncio.subprocess.PIPE,
        env=env,
        start_new_session=True,  # a Ctrl-C at the daemon's terminal is the daemon's to handle
        preexec_fn=_hang_up_with(os.getpid()) if _prctl is not None else None,
    )
    try:
        async with asyncio.timeout(VIRTUAL_START_TIMEOUT_S):
            first = await process.stdout.readline()
    except TimeoutError:
        process.kill()
        await process.wait()
        raise LinkTimeout(
            "the pty path on the virtual hub's first line", name, VIRTUAL_START_TIMEOUT_S
        ) from None
    path = first.decode("utf-8", "replace").strip()
    if not path.startswith("/"):
        if process.returncode is None:
            process.kill()
        err = (await process.stderr.read()).decode("utf-8", "replace").strip()
        await process.wait()
        raise LinkError(f"virtual hub {name} did not start: {err[-300:] or path!r}")
    return VirtualBackend(name, path, process)


def _hang_up_with(daemon_pid: int):
    """What the hub's process does before it starts (Linux): ask for SIGHUP when the daemon dies,
    even by `kill -9`, so a virtual hub never outlives its console; it finishes its program first,
    as a hub left on the table would (`openbricks_sim.virtual_hub`). Runs between fork and exec:
    nothing here may take a lock."""

    def ask():
        _prctl(_PR_SET_PDEATHSIG, signal.SIGHUP)
        if os.getppid() != daemon_pid:  # the daemon died before the request was in place
            os.kill(os.getpid(), signal.SIGHUP)

    return ask
