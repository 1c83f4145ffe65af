"""The virtual-hub link: a simulated hub process, reached over its stdin/stdout or its pty.

A virtual hub is `python -m openbricks_sim.virtual_hub --name NAME [--dir DIR] [--world W]`: a
process that behaves like a hub on the wire (raw REPL, raw-paste, host calls) with the simulator
behind it. User code runs in that process, never in ours, and closing the link ends the process.

- `VirtualHubLink` spawns it and speaks over its pipes (stdout carries only REPL bytes; its
  stderr is kept, the last lines of it explain an unexpected exit). A virtual hub behind pipes
  cannot reconnect: its process, and the hub's state, are gone with them.
- `spawn_pty_hub` starts it with `--pty` (the process prints the pty path on its first line) and
  returns a `SerialLink` on that path, which, like a USB hub, can be reopened.
"""

from __future__ import annotations

import asyncio
import sys
from collections import deque
from collections.abc import Sequence
from typing import Any

from openbricks_server.link.base import Link
from openbricks_server.link.errors import LinkDropped, LinkError, LinkTimeout
from openbricks_server.link.serial_link import SerialLink

MODULE = "openbricks_sim.virtual_hub"
STOP_GRACE_S = 2.0
STDERR_TAIL_LINES = 20


def virtual_hub_command(
    name: str,
    *,
    hub_dir: str | None = None,
    world: str | None = None,
    pty: bool = False,
    extra_args: Sequence[str] = (),
    python: str = sys.executable,
) -> list[str]:
    command = [python, "-m", MODULE, "--name", name]
    if hub_dir is not None:
        command += ["--dir", str(hub_dir)]
    if world is not None:
        command += ["--world", world]
    if pty:
        command.append("--pty")
    return command + list(extra_args)


async def _stop_process(process: asyncio.subprocess.Process) -> None:
    if process.returncode is not None:
        return
    process.terminate()
    try:
        async with asyncio.timeout(STOP_GRACE_S):
            await process.wait()
    except TimeoutError:
        process.kill()
        await process.wait()


class VirtualHubLink(Link):
    """A virtual hub process named `name`, spoken to over its stdin/stdout."""

    def __init__(
        self,
        name: str,
        *,
        hub_dir: str | None = None,
        world: str | None = None,
        extra_args: Sequence[str] = (),
        python: str = sys.executable,
        **kwargs: Any,
    ):
        super().__init__(name, **kwargs)
        self.command = virtual_hub_command(
            name, hub_dir=hub_dir, world=world, extra_args=extra_args, python=python
        )
        self.process: asyncio.subprocess.Process | None = None
        self._stderr_tail: deque[str] = deque(maxlen=STDERR_TAIL_LINES)
        self._tasks: list[asyncio.Task] = []

    def _describe(self) -> str:
        return "virtual hub process"

    @property
    def stderr_tail(self) -> str:
        return "\n".join(self._stderr_tail)

    async def _open(self) -> None:
        self.process = await asyncio.create_subprocess_exec(
            *self.command,
            stdin=asyncio.subprocess.PIPE,
            stdout=asyncio.subprocess.PIPE,
            stderr=asyncio.subprocess.PIPE,
        )
        self._tasks = [
            asyncio.create_task(self._pump_stdout(self.process)),
            asyncio.create_task(self._pump_stderr(self.process)),
        ]

    async def _pump_stdout(self, process: asyncio.subprocess.Process) -> None:
        while True:
            data = await process.stdout.read(65536)
            if not data:
                break
            self._received(data)
        code = await process.wait()
        tail = self.stderr_tail.strip().splitlines()
        last = f"; its last words: {tail[-1]}" if tail else ""
        self._dropped(f"the virtual hub process exited with code {code}{last}")

    async def _pump_stderr(self, process: asyncio.subprocess.Process) -> None:
        while True:
            line = await process.stderr.readline()
            if not line:
                return
            self._stderr_tail.append(line.decode("utf-8", "replace").rstrip())

    async def _send(self, data: bytes) -> None:
        process = self.process
        try:
            process.stdin.write(data)
            await process.stdin.drain()
        except (BrokenPipeError, ConnectionResetError) as err:
            raise LinkDropped(self.hub, f"the virtual hub process stopped reading ({err})") from None

    async def _close(self) -> None:
        process, self.process = self.process, None
        if process is not None:
            if process.stdin is not None and not process.stdin.is_closing():
                process.stdin.close()
            await _stop_process(process)
        for task in self._tasks:
            task.cancel()
        await asyncio.gather(*self._tasks, return_exceptions=True)
        self._tasks = []


class PtyHub:
    """A virtual hub process serving a pty; `link` is a SerialLink on it. `await stop()` ends both."""

    def __init__(self, process: asyncio.subprocess.Process, path: str, link: SerialLink):
        self.process = process
        self.path = path
        self.link = link
        # Whatever the process still prints must be read, or a full pipe would stall the hub.
        self._drains = [
            asyncio.create_task(_drain(process.stdout)),
            asyncio.create_task(_drain(process.stderr)),
        ]

    async def stop(self) -> None:
        await self.link.close()
        await _stop_process(self.process)
        await asyncio.gather(*self._drains, return_exceptions=True)


async def _drain(stream: asyncio.StreamReader) -> None:
    while await stream.read(65536):
        pass


async def spawn_pty_hub(
    name: str,
    *,
    hub_dir: str | None = None,
    world: str | None = None,
    extra_args: Sequence[str] = (),
    python: str = sys.executable,
    start_timeout_s: float = 20.0,
) -> PtyHub:
    """Start a virtual hub on a pty and connect a SerialLink to it."""
    command = virtual_hub_command(
        name, hub_dir=hub_dir, world=world, pty=True, extra_args=extra_args, python=python
    )
    process = await asyncio.create_subprocess_exec(
        *command,
        stdin=asyncio.subprocess.DEVNULL,
        stdout=asyncio.subprocess.PIPE,
        stderr=asyncio.subprocess.PIPE,
    )
    try:
        async with asyncio.timeout(start_timeout_s):
            first = await process.stdout.readline()
    except TimeoutError:
        await _stop_process(process)
        raise LinkTimeout("the pty path on the virtual hub's first line", name, start_timeout_s) from None
    path = first.decode("utf-8", "replace").strip()
    if not path.startswith("/"):
        await _stop_process(process)
        err = (await process.stderr.read()).decode("utf-8", "replace").strip()
        raise LinkError(f"virtual hub {name} did not start: first line {path!r}; stderr: {err[-500:]}")
    link = SerialLink(path, hub=name)
    hub = PtyHub(process, path, link)
    try:
        await link.connect()
    except BaseException:
        await hub.stop()
        raise
    return hub
