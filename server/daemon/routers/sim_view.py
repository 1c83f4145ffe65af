"""The pages of a sim run, on the daemon's own port and behind its token (any role may watch):

- `/sim/runs/ID/view/`: the live 3D view, forwarded from the run's viser server (HTTP and WebSocket).
  Once the run has ended it sends the browser to the replay.
- `/sim/runs/ID/replay/`: viser's own client playing the run's recording back with a timeline
  (`?playbackPath=` names the recording's download URL), to watch, scrub, and download.
"""

from __future__ import annotations

import asyncio
import importlib.util
from functools import cache
from pathlib import Path
from urllib.parse import urlencode

from fastapi import APIRouter, Depends, Request, WebSocket
from fastapi.responses import FileResponse, RedirectResponse, Response

from openbricks_server.daemon.auth import require_viewer
from openbricks_server.daemon.errors import ApiError
from openbricks_server.daemon.routers.sim import _check_id
from openbricks_server.daemon.sim.jobs import START_TIMEOUT_S
from openbricks_server.daemon.sim.proxy import forward_page

router = APIRouter(include_in_schema=False)


@cache
def viser_client_page() -> Path:
    """viser's client build (one self-contained page), found without importing viser here."""
    spec = importlib.util.find_spec("viser")
    if spec is None or spec.origin is None:
        raise ApiError(
            404,
            "replay_unavailable",
            "the 3D replay needs viser",
            "install the sim extra: pip install 'openbricks[sim]'",
        )
    return Path(spec.origin).parent / "client" / "build" / "index.html"


def _run(request, run_id: str) -> dict:
    row = request.app.state.ctx.store.sim_runs.get(_check_id(run_id))
    if row is None:
        raise ApiError.not_found(f"sim run {run_id}", "GET /api/sim/runs lists the sim runs")
    return row


def _to(path: str, request: Request) -> RedirectResponse:
    query = request.url.query
    return RedirectResponse(path + (f"?{query}" if query else ""), status_code=307)


@router.get("/sim/runs/{run_id}/view", dependencies=[Depends(require_viewer)])
async def view_slash(request: Request, run_id: str):
    return _to(f"/sim/runs/{_check_id(run_id)}/view/", request)


@router.get("/sim/runs/{run_id}/view/{path:path}", dependencies=[Depends(require_viewer)])
async def view_page(request: Request, run_id: str, path: str) -> Response:
    """The live view's page (and anything it loads); the replay once the run is over."""
    _run(request, run_id)
    jobs = request.app.state.ctx.sim
    job = jobs.live.get(run_id)
    if job is not None:
        try:
            await asyncio.wait_for(job.ready.wait(), START_TIMEOUT_S)
        except TimeoutError:
            pass
    if job is None or job.port is None or job.ended.is_set():
        if path:
            raise ApiError.not_found(
                f"{path!r} of sim run {run_id}'s view", "the run has ended: see its replay"
            )
        return RedirectResponse(f"/sim/runs/{run_id}/replay/", status_code=303)
    return await forward_page(jobs.http, job.port, path, request)


async def _socket(websocket: WebSocket, run_id: str) -> None:
    jobs = websocket.app.state.ctx.sim
    job = jobs.live.get(run_id)
    if job is not None and not job.ready.is_set():
        try:
            await asyncio.wait_for(job.ready.wait(), START_TIMEOUT_S)
        except TimeoutError:
            pass
    if job is None or job.relay is None or job.ended.is_set():
        await websocket.close(code=1008, reason="this sim run is not live: watch its replay")
        return
    await job.relay.serve(websocket)


@router.websocket("/sim/runs/{run_id}/view")
async def view_socket(websocket: WebSocket, run_id: str) -> None:
    await _socket(websocket, run_id)  # the middleware let only a signed-in caller with our Origin in


@router.websocket("/sim/runs/{run_id}/view/")
async def view_socket_slash(websocket: WebSocket, run_id: str) -> None:
    await _socket(websocket, run_id)


@router.get("/sim/runs/{run_id}/replay", dependencies=[Depends(require_viewer)])
async def replay_slash(request: Request, run_id: str):
    return _to(f"/sim/runs/{_check_id(run_id)}/replay/", request)


@router.get("/sim/runs/{run_id}/replay/", dependencies=[Depends(require_viewer)])
async def replay_page(request: Request, run_id: str) -> Response:
    """viser's client playing the run's recording (the recording's URL rides in `playbackPath`)."""
    row = _run(request, run_id)
    if row["recording"] is None:
        if run_id in request.app.state.ctx.sim.live:
            return RedirectResponse(f"/sim/runs/{run_id}/view/", status_code=303)
        raise ApiError.not_found(
            f"a recording of sim run {run_id}", "this run ended before its recording could be written"
        )
    if "playbackPath" not in request.query_params:
        query = urlencode({"playbackPath": f"/api/sim/runs/{run_id}/recording"})
        return RedirectResponse(f"/sim/runs/{run_id}/replay/?{query}", status_code=307)
    return FileResponse(viser_client_page(), media_type="text/html", headers={"cache-control": "no-cache"})
