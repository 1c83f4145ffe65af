"""A sim run's 3D view, forwarded from the run's viser server (127.0.0.1, no login of its own) to
browsers that reach the daemon with a token.

viser serves its page and its WebSocket on one port and its client connects to the WebSocket at the
page's own URL, so the page served under `/sim/runs/ID/view/` talks to `/sim/runs/ID/view`, which
lands here too. Pages stream through as they arrive.

The WebSockets of every browser watching one run share ONE connection to the run's viser server
(`ViewRelay`): viser encodes and compresses each frame once per connected client, on the threads of
the run's own process, so twenty browsers connected straight to it would cost the run twenty times
the work of one. The relay keeps every message viser sent on its connection; a browser that joins
later is sent them all first (they build the scene up exactly as they did for the first browser),
then the live ones. What browsers send (camera moves, panel clicks) goes up the shared connection.
Past RELAY_LOG_BYTES of kept messages a newcomer gets a connection of its own instead. A browser
whose backlog passes WATCHER_QUEUE messages (it stopped reading) is disconnected, so a slow browser
never holds up the run or the other watchers; reloading the page starts it afresh.
"""

from __future__ import annotations

import asyncio
import contextlib

import httpx
import websockets
from fastapi import Request, WebSocket
from fastapi.responses import StreamingResponse
from starlette.background import BackgroundTask
from websockets.asyncio.client import connect

from openbricks_server.daemon.errors import ApiError

CONNECT_TIMEOUT_S = 10.0
RELAY_LOG_BYTES = 64 * 1024 * 1024
WATCHER_QUEUE = 2000
READ_TIMEOUT_S = 30.0
SEND_TIMEOUT_S = 30.0
# What a page's answer may carry through (hop-by-hop headers stay behind).
PASSED_HEADERS = ("content-type", "content-encoding", "content-length", "cache-control", "last-modified")


def http_client() -> httpx.AsyncClient:
    return httpx.AsyncClient(
        timeout=httpx.Timeout(READ_TIMEOUT_S, connect=CONNECT_TIMEOUT_S),
        limits=httpx.Limits(max_connections=100, max_keepalive_connections=20),
        trust_env=False,  # 127.0.0.1 only: no proxy from the environment may sit in between
    )


async def forward_page(
    client: httpx.AsyncClient, port: int, path: str, request: Request
) -> StreamingResponse:
    headers = {
        k: v for k, v in request.headers.items() if k in ("accept", "accept-encoding", "if-modified-since")
    }
    upstream_request = client.build_request("GET", f"http://127.0.0.1:{port}/{path}", headers=headers)
    try:
        upstream = await client.send(upstream_request, stream=True)
    except httpx.HTTPError as exc:
        raise ApiError(
            502,
            "sim_view_unreachable",
            f"the run's 3D view did not answer ({type(exc).__name__})",
            "the run may just have ended: reload to see its replay",
        ) from None
    passed = {k: upstream.headers[k] for k in PASSED_HEADERS if k in upstream.headers}
    return StreamingResponse(
        upstream.aiter_raw(),
        status_code=upstream.status_code,
        headers=passed,
        background=BackgroundTask(upstream.aclose),
    )


async def _connect(port: int, subprotocols):
    return await connect(
        f"ws://127.0.0.1:{port}/",
        subprotocols=list(subprotocols) or None,
        open_timeout=CONNECT_TIMEOUT_S,
        max_size=None,
        compression=None,
        proxy=None,
    )


_UNREACHABLE = (OSError, TimeoutError, websockets.exceptions.WebSocketException)


class ViewRelay:
    """One run's shared connection to its viser server, and the browsers it feeds."""

    def __init__(self, port: int):
        self.port = port
        self._upstream = None
        self._opening = asyncio.Lock()
        self._log: list[bytes | str] = []  # every message viser sent on the shared connection
        self._log_bytes = 0
        self._watchers: set[asyncio.Queue] = set()
        self._pump: asyncio.Task | None = None

    @property
    def watchers(self) -> int:
        return len(self._watchers)

    async def serve(self, websocket: WebSocket) -> None:
        """Feed one browser's WebSocket from the shared connection until either side closes."""
        offered = list(websocket.scope.get("subprotocols") or [])
        async with self._opening:
            if self._upstream is None:
                try:
                    self._upstream = await _connect(self.port, offered)
                except _UNREACHABLE:
                    await websocket.close(code=1011, reason="the run's 3D view did not answer")
                    return
                self._pump = asyncio.create_task(self._read_upstream())
        upstream = self._upstream
        if self._log_bytes > RELAY_LOG_BYTES or upstream.subprotocol not in offered or self._pump.done():
            await forward_socket(websocket, self.port)  # a connection of its own
            return
        queue: asyncio.Queue = asyncio.Queue()
        for message in self._log:  # no await from the copy to joining: nothing is missed or doubled
            queue.put_nowait(message)
        self._watchers.add(queue)
        try:
            await websocket.accept(subprotocol=upstream.subprotocol)
            await _pair(websocket, queue, upstream)
        finally:
            self._watchers.discard(queue)
        with contextlib.suppress(Exception):
            await websocket.close()

    async def _read_upstream(self) -> None:
        try:
            async for message in self._upstream:
                self._log.append(message)
                self._log_bytes += len(message)
                for queue in list(self._watchers):
                    if queue.qsize() >= WATCHER_QUEUE:
                        self._watchers.discard(queue)
                        queue.put_nowait(None)  # it stopped reading: closed, not waited for
                    else:
                        queue.put_nowait(message)
        except websockets.exceptions.WebSocketException:
            pass
        finally:
            for queue in list(self._watchers):
                queue.put_nowait(None)  # the run's view is gone
            self._watchers.clear()

    async def close(self) -> None:
        if self._upstream is not None:
            await self._upstream.close()
        if self._pump is not None:
            with contextlib.suppress(BaseException):
                await self._pump


async def _pair(websocket: WebSocket, queue: asyncio.Queue, upstream) -> None:
    """Pass the queue's messages down to the browser and the browser's up, until one side ends."""

    async def down() -> None:
        while (message := await queue.get()) is not None:
            if isinstance(message, bytes):
                send = websocket.send_bytes(message)
            else:
                send = websocket.send_text(message)
            await asyncio.wait_for(send, SEND_TIMEOUT_S)

    async def up() -> None:
        while True:
            message = await websocket.receive()
            if message["type"] == "websocket.disconnect":
                return
            data = message.get("bytes")
            if data is None:
                data = message.get("text")
            if data is not None:
                await upstream.send(data)

    tasks = [asyncio.create_task(down()), asyncio.create_task(up())]
    try:
        await asyncio.wait(tasks, return_when=asyncio.FIRST_COMPLETED)
    finally:
        for task in tasks:
            task.cancel()
        for task in tasks:
            with contextlib.suppress(BaseException):
                await task


async def forward_socket(websocket: WebSocket, port: int) -> None:
    """Join the browser's WebSocket to a connection of its own to the run's viser server."""
    try:
        upstream = await _connect(port, websocket.scope.get("subprotocols") or [])
    except _UNREACHABLE:
        await websocket.close(code=1011, reason="the run's 3D view did not answer")
        return
    async with upstream:
        await websocket.accept(subprotocol=upstream.subprotocol)
        queue: asyncio.Queue = asyncio.Queue(WATCHER_QUEUE)

        async def read() -> None:
            try:
                async for message in upstream:
                    if queue.full():  # the browser stopped reading
                        break
                    queue.put_nowait(message)
            except websockets.exceptions.WebSocketException:
                pass
            while queue.full():
                queue.get_nowait()
            queue.put_nowait(None)

        reader = asyncio.create_task(read())
        try:
            await _pair(websocket, queue, upstream)
        finally:
            reader.cancel()
            with contextlib.suppress(BaseException):
                await reader
    with contextlib.suppress(Exception):
        await websocket.close()
