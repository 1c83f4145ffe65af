"""Competition mode and its match timer: read them (anyone signed in), change them (operators). While the
mode is on and a hub runs, uploads and new runs are refused with 409 `competition_locked`; see
`openbricks_server.daemon.competition`."""

from __future__ import annotations

from dataclasses import asdict

from fastapi import APIRouter, Depends, Request
from pydantic import BaseModel, Field

from openbricks_server.daemon.auth import Caller, require_operator, require_viewer
from openbricks_server.daemon.competition import MAX_MATCH_S, MIN_MATCH_S, Competition
from openbricks_server.daemon.store import now_ms

router = APIRouter(prefix="/competition", tags=["competition"], dependencies=[Depends(require_viewer)])


class CompetitionOut(BaseModel):
    on: bool
    match_s: int  # the match's length
    match_started_ms: int | None  # when the match timer was started (the daemon's clock), or null
    changed_by: str | None
    changed_ms: int | None
    server_ms: int  # the daemon's clock now, so a page on another computer can run the same timer
    running: list[str]  # the hubs running a program now
    locked: bool  # uploads and new runs are refused right now (the mode is on and a hub runs)


class CompetitionChange(BaseModel):
    """Fields left out stay as they are."""

    on: bool | None = Field(None, description="competition mode on or off (off also resets the timer)")
    match_s: int | None = Field(None, ge=MIN_MATCH_S, le=MAX_MATCH_S, description="the match's length")


def _out(request: Request) -> CompetitionOut:
    ctx = request.app.state.ctx
    competition: Competition = ctx.competition
    running = competition.running(ctx.hubs)
    return CompetitionOut(
        **asdict(competition.state),
        server_ms=now_ms(),
        running=running,
        locked=competition.state.on and bool(running),
    )


@router.get("", response_model=CompetitionOut)
async def get_competition(request: Request) -> CompetitionOut:
    """Whether competition mode is on, the match timer, and whether uploads are locked right now."""
    return _out(request)


@router.put("", response_model=CompetitionOut)
async def change_competition(
    request: Request, body: CompetitionChange, caller: Caller = Depends(require_operator)
) -> CompetitionOut:
    """Turn competition mode on or off, or set the match's length; every page sees it at once."""
    request.app.state.ctx.competition.change(caller.label, on=body.on, match_s=body.match_s)
    return _out(request)


@router.post("/match/start", response_model=CompetitionOut)
async def start_match(request: Request, caller: Caller = Depends(require_operator)) -> CompetitionOut:
    """Start (or restart) the match timer; needs competition mode on."""
    request.app.state.ctx.competition.change(caller.label, match="start")
    return _out(request)


@router.post("/match/reset", response_model=CompetitionOut)
async def reset_match(request: Request, caller: Caller = Depends(require_operator)) -> CompetitionOut:
    """Stop the match timer and set it back to the match's length."""
    request.app.state.ctx.competition.change(caller.label, match="reset")
    return _out(request)
