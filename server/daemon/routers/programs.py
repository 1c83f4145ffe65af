"""Stored programs with their version history: `PUT` saves a new version (after the checks of
`openbricks_server.daemon.programs`), older versions stay readable and can be restored. Programs are
renamed, deleted, imported from a file (`POST /programs`, never overwriting unless asked) and
downloaded as `.py` files.

The editor keeps what is being typed as a draft (`PUT /programs/{name}/draft`, a second or so after the
last key): unchecked text, one per name, there for a new program before its first save, so a page
switch, a reload or another computer finds the edit again. Saving the program clears its draft."""

from __future__ import annotations

import asyncio

from fastapi import APIRouter, Depends, Path, Query, Request
from fastapi.responses import Response
from pydantic import BaseModel, Field

from openbricks_server.daemon.auth import Caller, require_operator, require_viewer
from openbricks_server.daemon.errors import ApiError
from openbricks_server.daemon.programs import check_name, check_source

router = APIRouter(prefix="/programs", tags=["programs"], dependencies=[Depends(require_viewer)])
drafts_router = APIRouter(prefix="/drafts", tags=["programs"], dependencies=[Depends(require_viewer)])

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


class ProgramImport(BaseModel):
    name: str = Field(max_length=200, description="the program's name, e.g. square.py")
    source: str = Field(description="the file's text")
    replace: bool = Field(False, description="store it as a new version of an existing program of that name")


class Rename(BaseModel):
    new_name: str = Field(max_length=200, description="the program's new name, e.g. square_v2.py")


# A draft is kept even past what a hub would take (saving it says so): losing typing is worse.
DRAFT_MAX_CHARS = 1_000_000


class DraftText(BaseModel):
    source: str = Field(max_length=DRAFT_MAX_CHARS, description="the editor's text as it is now")
    base_version: int | None = Field(
        None, ge=1, le=2**31, description="the stored version the edit started from; null for a new program"
    )


class DraftInfo(BaseModel):
    name: str
    base_version: int | None
    who: str | None  # the token label that typed it
    updated_ms: int


class Draft(DraftInfo):
    source: str


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
    """Store the text as the program's newest version (checked first: name, size, text, syntax); the
    program's draft, now saved, is cleared."""
    return await _save(request, check_name(name), body.source, caller.label, "saved")


@router.get("/{name}/draft", response_model=Draft)
async def get_draft(request: Request, name: str = ProgramName) -> Draft:
    """The program's unsaved edit, if the editor left one (404 `not_found` when there is none)."""
    found = request.app.state.ctx.store.drafts.get(check_name(name))
    if found is None:
        raise ApiError.not_found(f"a draft of {name!r}", "the stored program is GET /api/programs/{name}")
    return Draft(**found)


@router.put("/{name}/draft", response_model=Draft)
async def put_draft(
    body: DraftText, request: Request, name: str = ProgramName, caller: Caller = Depends(require_operator)
) -> Draft:
    """Keep the editor's text as the program's draft (not checked, not a version; the newest one wins)."""
    drafts = request.app.state.ctx.store.drafts
    return Draft(**drafts.put(check_name(name), body.source, body.base_version, caller.label))


@router.delete("/{name}/draft", status_code=204, dependencies=[Depends(require_operator)])
async def discard_draft(request: Request, name: str = ProgramName) -> None:
    """Throw the unsaved edit away (nothing to throw away is fine too)."""
    request.app.state.ctx.store.drafts.delete(check_name(name))


@drafts_router.get("", response_model=list[DraftInfo])
async def list_drafts(request: Request) -> list[DraftInfo]:
    """Every program name with an unsaved edit (text left out), a new program's too."""
    return [DraftInfo(**d) for d in request.app.state.ctx.store.drafts.list()]


async def _save(request: Request, name: str, source: str, who: str, action: str) -> Saved:
    """Check and store `source` as `name`'s newest version, announced as `action` when it is new. The
    program's draft goes: the text the editor works on is now this version (saved, restored, imported)."""
    await asyncio.to_thread(check_source, name, source)
    ctx = request.app.state.ctx
    version, created = ctx.store.programs.save(name, source, who)
    ctx.store.drafts.delete(name)
    info = {k: v for k, v in version.items() if k != "source"}
    if created:
        ctx.events.publish("program", {"action": action, **info})
    return Saved(program=ProgramVersionInfo(**info), created=created)


def _exists(name: str) -> ApiError:
    return ApiError.conflict(
        "program_exists",
        f"a program named {name!r} is already stored",
        "choose another name, or delete or rename the stored one first",
        {"name": name},
    )


@router.post("", response_model=Saved, status_code=201)
async def import_program(
    body: ProgramImport, request: Request, caller: Caller = Depends(require_operator)
) -> Saved:
    """Store a program from a file's text (an upload from disk): refused with 409 when the name is taken,
    unless `replace` asks to add it as that program's newest version."""
    name = check_name(body.name)
    if not body.replace and request.app.state.ctx.store.programs.version(name, None) is not None:
        raise _exists(name)
    return await _save(request, name, body.source, caller.label, "imported")


@router.get(
    "/{name}/download",
    response_class=Response,
    responses={200: {"content": {"text/x-python": {}}, "description": "the program as a .py file"}},
)
async def download_program(
    request: Request, name: str = ProgramName, version: int | None = Query(None, ge=1, le=2**31)
) -> Response:
    """The program's text (the newest version, or `version`) as a file to save."""
    found = _program(request, name, version)
    return Response(
        found["source"].encode("utf-8"),
        media_type="text/x-python; charset=utf-8",
        headers={"content-disposition": f'attachment; filename="{found["name"]}"'},
    )


@router.post("/{name}/rename", response_model=ProgramVersionInfo)
async def rename_program(
    body: Rename, request: Request, name: str = ProgramName, caller: Caller = Depends(require_operator)
) -> ProgramVersionInfo:
    """Give a program, with all its versions, a new name (runs keep the name they ran under)."""
    old, new = check_name(name), check_name(body.new_name)
    ctx = request.app.state.ctx
    if old != new:
        outcome = ctx.store.programs.rename(old, new)
        if outcome == "taken":
            raise _exists(new)
        if outcome == "missing":
            raise ApiError.not_found(f"program {old!r}", "GET /api/programs lists the stored programs")
        ctx.store.drafts.rename(old, new)
        ctx.events.publish("program", {"action": "renamed", "name": new, "old_name": old})
    info = {k: v for k, v in _program(request, new, None).items() if k != "source"}
    return ProgramVersionInfo(**info)


@router.post("/{name}/versions/{version}/restore", response_model=Saved)
async def restore_version(
    request: Request,
    name: str = ProgramName,
    version: int = Path(ge=1, le=2**31),
    caller: Caller = Depends(require_operator),
) -> Saved:
    """Make an older version's text the newest version again (the versions in between stay)."""
    found = _program(request, name, version)
    return await _save(request, found["name"], found["source"], caller.label, "saved")


@router.delete("/{name}", status_code=204, dependencies=[Depends(require_operator)])
async def delete_program(request: Request, name: str = ProgramName) -> None:
    """Delete the program with all its versions (runs keep the exact source they ran)."""
    ctx = request.app.state.ctx
    ctx.store.drafts.delete(check_name(name))
    if not ctx.store.programs.delete(check_name(name)):
        raise ApiError.not_found(f"program {name!r}", "GET /api/programs lists the stored programs")
    ctx.events.publish("program", {"action": "deleted", "name": name})
