"""Stored programs with their version history: `PUT` saves a new version (after the checks of
`openbricks_server.daemon.programs`), older versions stay readable."""

from __future__ import annotations

import asyncio

from fastapi import APIRouter, Depends, Path, Request
from pydantic import BaseModel, Field

from openbricks_server.daemon.auth import Caller, require_operator, require_viewer
from openbricks_server.daemon.errors import ApiError
from openbricks_server.daemon.programs import check_name, check_source

router = APIRouter(prefix="/programs", tags=["programs"], dependencies=[Depends(require_viewer)])

ProgramName = Path(description="1-64 letters, digits, '_', '.', '-'; e.g. square.py", max_length=200)


class ProgramVersionInfo(BaseModel):
    name: str
    version: int
    sha256: str
    size: int  # bytes of UTF-8 source
    created_ms: int
    who: str | None  # the token label that saved it


class ProgramSource(ProgramVersionInfo):
    source: str


class ProgramText(BaseModel):
    source: str = Field(description="the program's Python source text")


class Saved(BaseModel):
    program: ProgramVersionInfo
    created: bool  # False when the text equals the newest version's (no new version added)


def _program(request: Request, name: str, version: int | None) -> dict:
    found = request.app.state.ctx.store.programs.version(check_name(name), version)
    if found is None:
        what = f"program {name!r}" + (f" version {version}" if version is not None else "")
        raise ApiError.not_found(what, "GET /api/programs lists the stored programs")
    return found


@router.get("", response_model=list[ProgramVersionInfo])
async def list_programs(request: Request) -> list[ProgramVersionInfo]:
    """Every stored program at its newest version."""
    return [ProgramVersionInfo(**p) for p in request.app.state.ctx.store.programs.list()]


@router.get("/{name}", response_model=ProgramSource)
async def get_program(request: Request, name: str = ProgramName) -> ProgramSource:
    return ProgramSource(**_program(request, name, None))


@router.get("/{name}/versions", response_model=list[ProgramVersionInfo])
async def list_versions(request: Request, name: str = ProgramName) -> list[ProgramVersionInfo]:
    _program(request, name, None)
    return [ProgramVersionInfo(**v) for v in request.app.state.ctx.store.programs.versions(name)]


@router.get("/{name}/versions/{version}", response_model=ProgramSource)
async def get_version(
    request: Request, name: str = ProgramName, version: int = Path(ge=1, le=2**31)
) -> ProgramSource:
    return ProgramSource(**_program(request, name, version))


@router.put("/{name}", response_model=Saved)
async def save_program(
    body: ProgramText,
    request: Request,
    name: str = ProgramName,
    caller: Caller = Depends(require_operator),
) -> Saved:
    """Store the text as the program's newest version (checked first: name, size, text, syntax)."""
    check_name(name)
    await asyncio.to_thread(check_source, name, body.source)
    ctx = request.app.state.ctx
    version, created = ctx.store.programs.save(name, body.source, caller.label)
    info = {k: v for k, v in version.items() if k != "source"}
    if created:
        ctx.events.publish("program", {"action": "saved", **info})
    return Saved(program=ProgramVersionInfo(**info), created=created)


@router.delete("/{name}", status_code=204, dependencies=[Depends(require_operator)])
async def delete_program(request: Request, name: str = ProgramName) -> None:
    """Delete the program with all its versions (runs keep the exact source they ran)."""
    ctx = request.app.state.ctx
    if not ctx.store.programs.delete(check_name(name)):
        raise ApiError.not_found(f"program {name!r}", "GET /api/programs lists the stored programs")
    ctx.events.publish("program", {"action": "deleted", "name": name})
