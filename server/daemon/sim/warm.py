"""Sim runs' children from a warm fork server, seen through asyncio like a spawned subprocess.

A console sim run's child would spend most of a second importing MuJoCo, numpy and the 3D view's
server before the program's first line. The daemon keeps one fork server (openbricks_sim.fork_server)
warm instead and asks it for each run's child: the child fences itself in first thing, as a spawned
one does. The server starts with the first sim run of the daemon's life (that run is spawned cold
meanwhile, so it waits no longer than it did before), and stays for the runs after it: a daemon
that never simulates never pays for one. What comes back looks like asyncio's Process to the job
that minds it (pid, returncode, stdin, stdout, wait()), so the job has one way to steer a child
however it was started. Where the OS cannot fork, or the server has gone, a child is spawned cold.
"""

from __future__ import annotations

import asyncio
import json
import logging
import os
import signal

from openbricks_sim.fork_server import START_TIMEOUT_S, ForkServer
from openbricks_sim.forked import ForkServerError

log = logging.getLogger("openbricks.console")


class WarmServer:
    """The daemon's fork server, (re)started on demand."""

    def __init__(self):
        self._server: ForkServer | None = None

    def _start(self) -> None:
        try:
            self._server = ForkServer()
        except OSError as exc:
            log.warning("sim runs start cold: the fork server did not start (%s)", exc)
            self._server = None

    async def start(
        self, target: str, args: list[str], *, cwd: str, stderr: int, limit: int
    ) -> WarmProcess | None:
        """The child, or None when there is no fork server to ask yet (the caller spawns one cold)."""
        if not hasattr(os, "fork"):
            return None
        if self._server is None:  # the first run: it goes cold while the server warms for the next
            self._start()
            return None
        if self._server.process.poll() is not None:  # it died: a new one for the runs to come
            log.warning(
                "the sim fork server ended (status %s); starting another", self._server.process.returncode
            )
            self._start()
            return None
        stdin_read, stdin_write = os.pipe()
        stdout_read, stdout_write = os.pipe()
        try:
            reply = self._server.request(target, args, [stdin_read, stdout_write, stderr], cwd)
        except ForkServerError as exc:
            log.warning("sim run starts cold: %s", exc)
            os.close(stdin_write)
            os.close(stdout_read)
            return None
        finally:  # the child's ends: the server holds its own copies now
            os.close(stdin_read)
            os.close(stdout_write)
        return await WarmProcess.attach(reply, stdin_write, stdout_read, limit)

    async def close(self) -> None:
        """No more runs: the server ends once its children have (the daemon stopped them first)."""
        if self._server is not None:
            await asyncio.get_running_loop().run_in_executor(None, self._server.close)
            self._server = None


class WarmProcess:
    """A forked child as asyncio.subprocess.Process shows one: pid, returncode, stdin, stdout, wait()."""

    def __init__(self, pid: int, stdin: asyncio.StreamWriter, stdout: asyncio.StreamReader, reply):
        self.pid = pid
        self.returncode: int | None = None
        self.stdin = stdin
        self.stdout = stdout
        self._reply = reply
        self._waiter: asyncio.Task | None = None

    @classmethod
    async def attach(cls, reply, stdin_fd: int, stdout_fd: int, limit: int) -> WarmProcess:
        loop = asyncio.get_running_loop()
        stdout = asyncio.StreamReader(limit=limit)
        await loop.connect_read_pipe(
            lambda: asyncio.StreamReaderProtocol(stdout), os.fdopen(stdout_fd, "rb", 0)
        )
        transport, protocol = await loop.connect_write_pipe(
            lambda: asyncio.StreamReaderProtocol(asyncio.StreamReader()), os.fdopen(stdin_fd, "wb", 0)
        )
        stdin = asyncio.StreamWriter(transport, protocol, None, loop)
        reply_reader, reply_writer = await asyncio.open_unix_connection(sock=reply)
        try:
            first = await asyncio.wait_for(reply_reader.readline(), START_TIMEOUT_S)
            pid = int(json.loads(first)["pid"])
        except (TimeoutError, ValueError, KeyError, TypeError):
            transport.close()
            reply_writer.close()
            raise ForkServerError(f"the fork server did not start the child: {first!r}") from None
        return cls(pid, stdin, stdout, (reply_reader, reply_writer))

    async def wait(self) -> int:
        if self._waiter is None:
            self._waiter = asyncio.ensure_future(self._read_exit())
        return await asyncio.shield(self._waiter)

    async def _read_exit(self) -> int:
        reader, writer = self._reply
        line = await reader.readline()
        try:
            self.returncode = int(json.loads(line)["exit"])
        except (ValueError, KeyError, TypeError):  # the server went away first: the end is unknown
            self.returncode = -signal.SIGKILL
        writer.close()
        if not self.stdin.is_closing():
            self.stdin.close()
        return self.returncode
