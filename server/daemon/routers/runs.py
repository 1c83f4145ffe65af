"""The run history: search, one run with its source, its output and telemetry, and exports."""

from __future__ import annotations

import asyncio
import re
from datetime import datetime
from typing import Literal

from fastapi import APIRouter, Depends, Query, Request
from fastapi.responses import PlainTextResponse, Response
from pydantic import BaseModel

from openbricks_server.daemon.auth import require_viewer
from openbricks_server.daemon.errors import ApiError
from openbricks_server.daemon.store import RunQuery
from openbricks_server.daemon.store.export import run_json, run_text, runs_zip

router = APIRouter(prefix="/runs", tags=["runs"], dependencies=[Depends(require_viewer)])

_ULID = re.compile(r"^[0-9A-HJKMNP-TV-Z]{26}$")
Outcome = Literal[
    "finished",
    "error",
    "stopped",
    "dropped",
    "interrupted",
    "running",
    # how a sim run can end besides (its exit reason)
    "time_limit",
    "wall_limit",
    "cpu_limit",
    "memory_limit",
    "reset",
]
Origin = Literal["daemon", "button", "log", "sim"]


class RunSummary(BaseModel):
    run_id: str
    hub_id: str
    origin: str
    program_name: str | None
    program_sha256: str | None
    slot: int | None
    who: str | None
    started_ms: int
    ended_ms: int | None
    outcome: str | None  # None while the run is on
    detail: str | None
    line_count: int


class Gap(BaseModel):
    reason: str
    since_ms: int
    until_ms: int | None


class RunDetail(RunSummary):
    source: str | None  # the exact text that ran, when the daemon staged it
    gaps: list[Gap]


class Line(BaseModel):
    line_no: int
    text: str
    hub_ms: int | None
    recv_ms: int


class OutputPage(BaseModel):
    lines: list[Line]
    next_after: int  # pass as `after` for the next page
    more: bool


class Sample(BaseModel):
    name: str
    value: float
    hub_ms: int | None
    recv_ms: int


class RunExport(RunDetail):
    lines: list[Line]
    telemetry: list[Sample]


def _ms(when: datetime | None) -> int | None:
    return None if when is None else int(when.timestamp() * 1000)  # naive times are the daemon's local time


def _query(
    hub: str | None = Query(None, max_length=200, description="hub id or name"),
    q: str | None = Query(None, max_length=500, description="words in the output or the program name"),
    since: datetime | None = Query(None, description="started at or after (ISO 8601; local time if no zone)"),
    until: datetime | None = Query(None, description="started before"),
    outcome: Outcome | None = Query(None),
    origin: Origin | None = Query(None),
    program: str | None = Query(None, max_length=200),
    before: str | None = Query(None, description="a run id: only older runs (paging)"),
    limit: int = Query(50, ge=1, le=1000),
) -> RunQuery:
    if before is not None:
        _check_id(before)
    try:
        since_ms, until_ms = _ms(since), _ms(until)
    except (OverflowError, OSError, ValueError):
        raise ApiError.invalid("bad_date", "since/until is out of range", "give an ISO 8601 date") from None
    return RunQuery(hub, q, since_ms, until_ms, outcome, origin, program, before, limit)


def _check_id(run_id: str) -> str:
    if not _ULID.fullmatch(run_id):
        raise ApiError.invalid(
            "bad_run_id",
            f"{run_id[:40]!r} is not a run id",
            "run ids are 26 characters, e.g. from GET /api/runs",
        )
    return run_id


def _run(request: Request, run_id: str) -> dict:
    run = request.app.state.ctx.store.runs.get(_check_id(run_id))
    if run is None:
        raise ApiError.not_found(f"run {run_id}", "GET /api/runs lists the runs")
    return run


@router.get("", response_model=list[RunSummary])
async def search_runs(request: Request, query: RunQuery = Depends(_query)) -> list[RunSummary]:
    """Runs newest first, narrowed by hub, text, date, outcome, origin and program."""
    request.app.state.ctx.hub_events.flush()
    found = await asyncio.to_thread(request.app.state.ctx.store.runs.search, query)  # FTS over a long history
    return [RunSummary(**r) for r in found]


@router.get(
    "/export",
    response_class=Response,
    responses={200: {"content": {"application/zip": {}}, "description": "a zip: RUN_ID.txt and RUN_ID.json"}},
)
async def export_runs(request: Request, query: RunQuery = Depends(_query)) -> Response:
    """The runs a search finds, each as text and JSON, in one zip."""
    ctx = request.app.state.ctx
    ctx.hub_events.flush()
    runs = ctx.store.runs
    data = await asyncio.to_thread(lambda: runs_zip(runs, runs.search(query)))  # off the event loop
    return Response(
        data,
        media_type="application/zip",
        headers={"content-disposition": 'attachment; filename="openbricks-runs.zip"'},
    )


@router.get("/{run_id}", response_model=RunDetail)
async def get_run(request: Request, run_id: str) -> RunDetail:
    run = _run(request, run_id)
    gaps = request.app.state.ctx.store.runs.gaps(run_id)
    return RunDetail(**run, gaps=[Gap(**g) for g in gaps])


@router.get("/{run_id}/output", response_model=OutputPage)
async def get_output(
    request: Request,
    run_id: str,
    after: int = Query(0, ge=0, le=2**62, description="only lines after this line number"),
    limit: int = Query(1000, ge=1, le=10_000),
) -> OutputPage:
    _run(request, run_id)
    ctx = request.app.state.ctx
    ctx.hub_events.flush()
    lines = ctx.store.runs.lines(run_id, after, limit + 1)
    more = len(lines) > limit
    lines = lines[:limit]
    return OutputPage(
        lines=[Line(**ln) for ln in lines], next_after=lines[-1]["line_no"] if lines else after, more=more
    )


@router.get("/{run_id}/telemetry", response_model=list[Sample])
async def get_telemetry(
    request: Request, run_id: str, name: str | None = Query(None, max_length=200)
) -> list[Sample]:
    _run(request, run_id)
    ctx = request.app.state.ctx
    ctx.hub_events.flush()
    return [Sample(**s) for s in ctx.store.runs.telemetry(run_id, name)]


@router.get(
    "/{run_id}/export",
    response_model=RunExport,
    responses={200: {"content": {"text/plain": {}}, "description": "JSON (default) or text"}},
)
async def export_run(request: Request, run_id: str, format: Literal["json", "text"] = Query("json")):
    """One run as JSON (everything) or as the text a terminal showed, with a header."""
    run = _run(request, run_id)
    ctx = request.app.state.ctx
    ctx.hub_events.flush()
    if format == "text":
        return PlainTextResponse(
            await asyncio.to_thread(run_text, ctx.store.runs, run),
            headers={"content-disposition": f'attachment; filename="{run_id}.txt"'},
        )
    return RunExport(**await asyncio.to_thread(run_json, ctx.store.runs, run))
