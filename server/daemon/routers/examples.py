"""The shipped example programs (openbricks_server.examples), and opening one as a stored program.

Opening an example copies it into the programs store under a name of its own, so editing, running and
versioning it is what the team does with any program, and the example itself stays as shipped for the
next person who opens it.
"""

from __future__ import annotations

import asyncio

from fastapi import APIRouter, Depends, Path, Request
from pydantic import BaseModel, Field

from openbricks_server import examples
from openbricks_server.daemon.auth import Caller, require_operator, require_viewer
from openbricks_server.daemon.errors import ApiError
from openbricks_server.daemon.programs import check_name, check_source
from openbricks_server.daemon.routers.programs import ProgramVersionInfo

router = APIRouter(prefix="/examples", tags=["examples"], dependencies=[Depends(require_viewer)])

ExampleId = Path(description="the example's file name without .py, e.g. drivebase_square", max_length=64)
MAX_COPIES = 99


class ExampleInfo(BaseModel):
    id: str = Field(description="the file name without .py: drivebase_square")
    title: str
    group: str = Field(description="drive_base, sensors, line_following or competition")
    group_title: str = Field(description="the group as the manual names it: Drive base")
    summary: str = Field(description="what the program does, from its docstring")
    file: str = Field(description="the file name: drivebase_square.py")


class ExampleSource(ExampleInfo):
    source: str


class OpenExample(BaseModel):
    name: str | None = Field(
        None,
        description="the stored program's name; by default the example's file name, numbered "
        "(drivebase_square-2.py) when a program already has it",
    )


class OpenedExample(BaseModel):
    example: str
    program: ProgramVersionInfo


def _example(example_id: str) -> examples.Example:
    try:
        return examples.find(example_id)
    except examples.ExampleNotFound:
        raise ApiError.not_found(f"example {example_id!r}", "GET /api/examples lists them") from None


def _info(example: examples.Example) -> ExampleInfo:
    return ExampleInfo(
        id=example.id,
        title=example.title,
        group=example.group,
        group_title=example.group_title,
        summary=example.summary,
        file=example.file,
    )


def _free_name(taken: set[str], file: str) -> str:
    """`file`, or `stem-N.py` with the smallest N not taken: a copy never overwrites a team's program."""
    if file not in taken:
        return file
    stem = file.removesuffix(".py")
    for n in range(2, MAX_COPIES + 1):
        candidate = f"{stem}-{n}.py"
        if candidate not in taken:
            return candidate
    raise ApiError.conflict(
        "too_many_copies",
        f"{MAX_COPIES} programs are named after {file} already",
        "delete some of them, or give the copy a name",
    )


@router.get("", response_model=list[ExampleInfo])
async def list_examples() -> list[ExampleInfo]:
    """Every shipped example, grouped as the manual's chapters are (drive base, sensors, line following,
    competition), in the order to try them."""
    return [_info(e) for e in await asyncio.to_thread(examples.catalogue)]


@router.get("/{example_id}", response_model=ExampleSource)
async def get_example(example_id: str = ExampleId) -> ExampleSource:
    example = _example(example_id)
    return ExampleSource(**_info(example).model_dump(), source=examples.source(example))


@router.post("/{example_id}/open", response_model=OpenedExample, status_code=201)
async def open_example(
    request: Request,
    body: OpenExample | None = None,
    example_id: str = ExampleId,
    caller: Caller = Depends(require_operator),
) -> OpenedExample:
    """Copy the example into the stored programs as a new program (version 1) and return it."""
    example = _example(example_id)
    text = examples.source(example)
    await asyncio.to_thread(check_source, example.file, text)
    ctx = request.app.state.ctx
    # From here to the save nothing awaits: two opens at once cannot both take the same free name.
    taken = {p["name"] for p in ctx.store.programs.list()}
    wanted = body.name if body is not None and body.name else None
    if wanted is not None:
        check_name(wanted)
        if wanted in taken:
            raise ApiError.conflict(
                "program_exists",
                f"a program named {wanted!r} exists already",
                "pick another name, or leave the name out for a numbered one",
            )
        name = wanted
    else:
        name = _free_name(taken, example.file)
    version, _ = ctx.store.programs.save(name, text, caller.label)
    info = {k: v for k, v in version.items() if k != "source"}
    ctx.events.publish("program", {"action": "saved", **info})
    return OpenedExample(example=example.id, program=ProgramVersionInfo(**info))
