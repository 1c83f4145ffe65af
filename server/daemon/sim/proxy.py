"""A sim run's 3D view, forwarded from the run's viser server (127.0.0.1, no login of its own) to
browsers that reach the daemon with a token.

viser serves its page and its WebSocket on one port and its client connects to the WebSocket at the
page's own URL, so the page served under `/sim/runs/ID/view/` talks to `/sim/runs/ID/view`, which
lands here too. Both directions stream: a page is passed on as it arrives, WebSocket messages one by
one, and a browser that stops reading for SEND_TIMEOUT_S is disconnected rather than let its backlog
grow (viser keeps a queue per client, so a slow browser never holds up the run or other watchers).
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


async def forward_socket(websocket: WebSocket, port: int) -> None:
    """Join the browser's WebSocket to the run's viser server until either side closes."""
    try:
        upstream = await connect(
            f"ws://127.0.0.1:{port}/",
            subprotocols=list(websocket.scope.get("subprotocols") or []) or None,
            open_timeout=CONNECT_TIMEOUT_S,
            max_size=None,
            compression=None,
            proxy=None,
        )
    except (OSError, TimeoutError, websockets.exceptions.WebSocketException):
        await websocket.close(code=1011, reason="the run's 3D view did not answer")
        return
    async with upstream:
        await websocket.accept(subprotocol=upstream.subprotocol)

        async def down() -> None:
            async for message in upstream:
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
    with contextlib.suppress(Exception):
        await websocket.close()
