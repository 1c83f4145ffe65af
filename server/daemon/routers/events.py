"""The event stream's WebSocket: `/api/events?since=SEQ&boot=BOOT&batch_ms=MS`.

The server sends envelopes `{"seq", "type", "hub", "run", "ts", "data"}` (see
`openbricks_server.daemon.events`), one per text frame; with `batch_ms`, each frame is instead a JSON
array of the envelopes ready then, at most one frame every `batch_ms` (the browser console asks for
one a display frame: ten busy hubs are a thousand messages a second, each a task for the page).
A client may send commands as JSON objects `{"cmd": NAME, "id": ANY, ...}`; each gets a `reply`
(`{"id", "cmd", "ok", "result" | "error"}`), and garbage gets a reply with an error, never a dropped
connection. Commands are registered with `ws_command`; a mutating one goes through the same role check
and audit as the REST routes.
"""

from __future__ import annotations

import asyncio
import contextlib
import json
from collections.abc import Awaitable, Callable
from dataclasses import dataclass

from fastapi import APIRouter, Query, WebSocket, WebSocketDisconnect

from openbricks_server.daemon.auth import Caller, operator_action
from openbricks_server.daemon.errors import ApiError
from openbricks_server.daemon.events import control
from openbricks_server.daemon.routers.hub_lookup import hub_manager

router = APIRouter(tags=["events"])

SEND_TIMEOUT_S = 30.0  # a client that takes longer than this to accept a batch of messages is disconnected
MAX_COMMAND_BYTES = 64 * 1024

Handler = Callable[[WebSocket, Caller, dict], Awaitable[dict | None]]


@dataclass(frozen=True)
class WsCommand:
    name: str
    handler: Handler
    mutating: bool


COMMANDS: dict[str, WsCommand] = {}


def ws_command(name: str, *, mutating: bool) -> Callable[[Handler], Handler]:
    """Register `handler(websocket, caller, message) -> result` as the WebSocket command `name`."""

    def register(handler: Handler) -> Handler:
        COMMANDS[name] = WsCommand(name, handler, mutating)
        return handler

    return register


@ws_command("ping", mutating=False)
async def _ping(websocket: WebSocket, caller: Caller, message: dict) -> dict:
    return {"seq": websocket.app.state.ctx.events.seq}


@ws_command("stop_all", mutating=True)
async def _stop_all(websocket: WebSocket, caller: Caller, message: dict) -> dict:
    """STOP ALL from an open page without a round of HTTP: every connected hub, one report per hub."""
    return {"hubs": await hub_manager(websocket.app.state.ctx).stop_all(caller.label)}


@router.websocket("/events")
async def events(
    websocket: WebSocket,
    since: int | None = Query(None, ge=0, description="the last seq this client received"),
    boot: str | None = Query(None, max_length=64, description="the boot id of that seq (from hello)"),
    batch_ms: int | None = Query(
        None,
        ge=1,
        le=1000,
        description="send JSON arrays of envelopes, at most one frame per this many ms (omitted: one "
        "envelope per frame, each as soon as it happens)",
    ),
):
    bus = websocket.app.state.ctx.events
    caller: Caller = websocket.scope["state"]["caller"]
    await websocket.accept()
    subscriber, first = bus.subscribe(since, boot)
    lock = asyncio.Lock()

    async def send(texts: list[str]) -> None:
        async with lock, asyncio.timeout(SEND_TIMEOUT_S):
            if batch_ms:
                await websocket.send_text(f"[{','.join(texts)}]")
                return
            for text in texts:
                await websocket.send_text(text)

    async def reply(text: str) -> None:
        await send([text])

    try:
        await send(first)
        pump = asyncio.create_task(subscriber.pump(send, (batch_ms or 0) / 1000), name="events-pump")
        try:
            await _serve_commands(websocket, caller, reply)
        finally:
            pump.cancel()
            with contextlib.suppress(asyncio.CancelledError, Exception):
                await pump
    except (WebSocketDisconnect, TimeoutError, RuntimeError):
        pass
    finally:
        bus.unsubscribe(subscriber)


async def _serve_commands(websocket: WebSocket, caller: Caller, send) -> None:
    while True:
        message = await websocket.receive()
        if message["type"] == "websocket.disconnect":
            return
        text = message.get("text")
        if text is None:
            await send(_error_reply(None, None, "bad_message", "send commands as JSON text frames"))
            continue
        if len(text) > MAX_COMMAND_BYTES:
            await send(
                _error_reply(None, None, "bad_message", f"commands are at most {MAX_COMMAND_BYTES} bytes")
            )
            continue
        try:
            command = json.loads(text)
        except ValueError:
            await send(_error_reply(None, None, "bad_message", 'not JSON; send {"cmd": NAME, ...}'))
            continue
        if not isinstance(command, dict) or not isinstance(command.get("cmd"), str):
            await send(_error_reply(None, None, "bad_message", 'send a JSON object with a "cmd" string'))
            continue
        await send(await _run_command(websocket, caller, command))


async def _run_command(websocket: WebSocket, caller: Caller, command: dict) -> str:
    name, ident = command["cmd"], command.get("id")
    found = COMMANDS.get(name)
    if found is None:
        known = ", ".join(sorted(COMMANDS))
        return _error_reply(ident, name, "unknown_command", f"no command {name[:40]!r}; known: {known}")
    try:
        if found.mutating:
            with operator_action(websocket, caller, f"WS {name}"):
                result = await found.handler(websocket, caller, command)
        else:
            result = await found.handler(websocket, caller, command)
    except ApiError as exc:
        body = exc.body.model_dump(exclude_none=True)
        return control("reply", {"id": ident, "cmd": name, "ok": False, "error": body})
    return control("reply", {"id": ident, "cmd": name, "ok": True, "result": result})


def _error_reply(ident, name, error: str, message: str) -> str:
    body = {"error": error, "message": message, "hint": "see /api/events in the docs for the commands"}
    return control("reply", {"id": ident, "cmd": name, "ok": False, "error": body})
