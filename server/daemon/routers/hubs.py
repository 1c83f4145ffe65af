"""Hubs: list, inspect, connect/disconnect, identify, run, upload, stop, stop-all, the hub's own
run logs and its REPL. A hub is addressed by its stable id (`virtual:SimHub-1`, `ble:24:0A:...`) or its
current name; the routes never know which kind of hub they talk to.

Operations are one at a time per hub: a second caller gets 409 `hub_busy` naming the holder
(operation, who, since when). `stop` and `stop-all` go around that. A run answers once the hub has
started the program, with its run id; its output, telemetry and end follow on the event stream.
"""

from __future__ import annotations

import asyncio

from fastapi import APIRouter, Depends, Path, Request
from pydantic import BaseModel, Field, model_validator

from openbricks_server.compile import MAX_PROGRAM_BYTES, Program, ProgramError, compile_program
from openbricks_server.daemon.auth import Caller, require_operator, require_viewer
from openbricks_server.daemon.competition import unlocked
from openbricks_server.daemon.errors import ApiError
from openbricks_server.daemon.hubs.actor import HubActor
from openbricks_server.daemon.programs import check_name, check_source
from openbricks_server.daemon.routers.hub_lookup import find_hub, hub_errors, hub_manager

router = APIRouter(prefix="/hubs", tags=["hubs"], dependencies=[Depends(require_viewer)])

HubRef = Path(description="the hub's id (e.g. virtual:SimHub-1) or its current name", max_length=200)
SOURCE_MAX_CHARS = 300_000
# Operators only, and refused while competition mode locks uploads and new runs.
RUN_ALLOWED = Depends(unlocked("start a run"))
UPLOAD_ALLOWED = Depends(unlocked("upload a program"))
REPL_ALLOWED = Depends(unlocked("use a hub's REPL"))
REPL_MAX_CHARS = 20_000


class Holder(BaseModel):
    operation: str
    who: str
    since_ms: int


class HubOut(BaseModel):
    hub_id: str
    name: str
    kind: str
    address: str
    status: str
    rssi: int | None
    last_seen_ms: int | None
    firmware: str | None
    capabilities: dict
    staged_program: str | None
    run_id: str | None
    run_started_ms: int | None
    holder: Holder | None
    last_error: str | None


class HubList(BaseModel):
    hubs: list[HubOut]
    ble: str  # the Bluetooth scan's state: scanning, unavailable (and why), off (--no-ble)


class ProgramRequest(BaseModel):
    """A program as text (`source`, named `name`) or a stored program (`program`, optionally `version`)."""

    source: str | None = Field(None, max_length=SOURCE_MAX_CHARS)
    name: str = Field("program.py", max_length=200, description="the file name tracebacks show")
    program: str | None = Field(None, max_length=200, description="a stored program's name")
    version: int | None = Field(None, ge=1, le=2**31)

    @model_validator(mode="after")
    def _one_of(self):
        if (self.source is None) == (self.program is None):
            raise ValueError("give either `source` (program text) or `program` (a stored program's name)")
        return self


class UploadRequest(ProgramRequest):
    path: str | None = Field(
        None, max_length=200, description="hub file to write verbatim instead of staging the program"
    )


class RunStarted(BaseModel):
    run_id: str
    hub_id: str


class Uploaded(BaseModel):
    hub_id: str
    path: str
    bytes: int


class Identified(BaseModel):
    hub_id: str
    identify_ms: int


class IdentifyRequest(BaseModel):
    duration_ms: int = Field(3000, ge=1, le=30000)


class ReplInput(BaseModel):
    code: str = Field(min_length=1, max_length=REPL_MAX_CHARS, description="a line (or block) of Python")


class ReplOutput(BaseModel):
    hub_id: str
    output: str  # what the code printed; an expression's value as the interactive prompt shows it
    error: str | None  # the hub's traceback when the code raised (KeyboardInterrupt after Stop)


class StopReport(BaseModel):
    hub: str
    name: str
    stopped: bool
    detail: str


class StopAll(BaseModel):
    hubs: list[StopReport]


class LogEntry(BaseModel):
    index: int
    slot: int
    bytes: int


class LogLine(BaseModel):
    line_no: int
    text: str
    hub_ms: int | None


class LogText(BaseModel):
    hub_id: str
    index: int
    started_ms: int
    trigger: str | None
    outcome: str | None
    detail: str | None
    lines: list[LogLine]
    text: str  # the log as the hub keeps it: `<epoch ms> <text>` lines, framing included


def _out(actor: HubActor) -> HubOut:
    state = actor.state
    return HubOut(
        hub_id=state.hub_id,
        name=state.name,
        kind=state.kind,
        address=state.address,
        status=state.status,
        rssi=state.rssi,
        last_seen_ms=state.last_seen_ms,
        firmware=state.firmware,
        capabilities=dict(state.capabilities),
        staged_program=state.staged_program,
        run_id=state.run_id,
        run_started_ms=state.run_started_ms,
        holder=Holder(**state.holder) if state.holder else None,
        last_error=actor.last_error,
    )


async def _program(request: Request, body: ProgramRequest) -> Program:
    """The request's program, checked (name, size, text, syntax) and compiled with mpy-cross."""
    if body.program is not None:
        name = check_name(body.program)
        found = request.app.state.ctx.store.programs.version(name, body.version)
        if found is None:
            what = f"program {name!r}" + (f" version {body.version}" if body.version else "")
            raise ApiError.not_found(what, "GET /api/programs lists the stored programs")
        name, source = found["name"], found["source"]
    else:
        name, source = check_name(body.name), body.source
    check_source(name, source)
    try:
        return await asyncio.to_thread(compile_program, Program(name, source))
    except ProgramError as exc:
        raise ApiError.invalid("program_invalid", str(exc), "fix the program and send it again") from None


@router.get("", response_model=HubList)
async def list_hubs(request: Request) -> HubList:
    """Every hub the daemon knows: virtual, USB and BLE (seen on the scan), with status and holder."""
    hubs = hub_manager(request.app.state.ctx)
    return HubList(hubs=[_out(actor) for actor in hubs.list()], ble=hubs.ble_status)


@router.post("/stop-all", response_model=StopAll)
async def stop_all(request: Request, caller: Caller = Depends(require_operator)) -> StopAll:
    """Stop every hub at once (Ctrl-C around any queue); one report per hub."""
    reports = await hub_manager(request.app.state.ctx).stop_all(caller.label)
    return StopAll(hubs=[StopReport(**report) for report in reports])


@router.get("/{hub}", response_model=HubOut)
async def get_hub(request: Request, hub: str = HubRef) -> HubOut:
    return _out(find_hub(request.app.state.ctx, hub))


@router.post("/{hub}/connect", response_model=HubOut)
async def connect(request: Request, hub: str = HubRef, caller: Caller = Depends(require_operator)) -> HubOut:
    """Connect (entering the raw REPL, reading its firmware, setting its clock, reading its run logs)
    and keep it connected, reconnecting after drops, until disconnected."""
    actor = find_hub(request.app.state.ctx, hub)
    with hub_errors():
        await actor.connect()
    return _out(actor)


@router.post("/{hub}/disconnect", response_model=HubOut)
async def disconnect(
    request: Request, hub: str = HubRef, caller: Caller = Depends(require_operator)
) -> HubOut:
    """Give the hub back to its launcher (its button works) and close the link."""
    actor = find_hub(request.app.state.ctx, hub)
    with hub_errors():
        await actor.disconnect(caller.label)
    return _out(actor)


@router.post("/{hub}/identify", response_model=Identified)
async def identify(
    request: Request,
    body: IdentifyRequest | None = None,
    hub: str = HubRef,
    caller: Caller = Depends(require_operator),
) -> Identified:
    """Blink the hub's status LED white for a few seconds, to find it on the table."""
    actor = find_hub(request.app.state.ctx, hub)
    with hub_errors():
        reply = await actor.identify(who=caller.label, duration_ms=(body or IdentifyRequest()).duration_ms)
    return Identified(hub_id=actor.hub_id, identify_ms=reply["identify_ms"])


@router.post("/{hub}/run", response_model=RunStarted)
async def run(
    body: ProgramRequest,
    request: Request,
    hub: str = HubRef,
    caller: Caller = RUN_ALLOWED,
) -> RunStarted:
    """Check, compile, stage and run a program; answers once the hub started it."""
    actor = find_hub(request.app.state.ctx, hub)
    program = await _program(request, body)
    with hub_errors():
        run_id = await actor.run(program, who=caller.label, program_name=program.filename)
    return RunStarted(run_id=run_id, hub_id=actor.hub_id)


@router.post("/{hub}/upload", response_model=Uploaded)
async def upload(
    body: UploadRequest,
    request: Request,
    hub: str = HubRef,
    caller: Caller = UPLOAD_ALLOWED,
) -> Uploaded:
    """Stage a program as the hub's button program (or, with `path`, store its text there verbatim)."""
    actor = find_hub(request.app.state.ctx, hub)
    if body.path is not None and (
        not body.path.startswith("/") or body.path.endswith("/") or ".." in body.path
    ):
        raise ApiError.invalid(
            "bad_path", f"path {body.path!r}: give an absolute hub file path", "e.g. /lib/tools.py"
        )
    if body.path is not None and body.source is not None:
        # A file stored as it is (a helper module, data): only its name and size are checked.
        check_name(body.name)
        if len(body.source.encode("utf-8")) > MAX_PROGRAM_BYTES:
            raise ApiError(413, "too_large", f"{body.name} is larger than a hub accepts", "split it up")
        program = Program(body.name, body.source)
    else:
        program = await _program(request, body)
    with hub_errors():
        done = await actor.upload(program, who=caller.label, path=body.path)
    return Uploaded(hub_id=actor.hub_id, path=done["path"], bytes=done["bytes"])


@router.post("/{hub}/repl", response_model=ReplOutput)
async def repl(
    body: ReplInput, request: Request, hub: str = HubRef, caller: Caller = REPL_ALLOWED
) -> ReplOutput:
    """Run one entry in the hub's raw REPL, as one operation (409 while something else holds the hub;
    Stop interrupts an entry that loops). Names defined by one entry stay for the next."""
    actor = find_hub(request.app.state.ctx, hub)
    with hub_errors():
        done = await actor.repl(body.code, who=caller.label)
    return ReplOutput(hub_id=actor.hub_id, output=done["output"], error=done["error"])


@router.post("/{hub}/stop", response_model=StopReport)
async def stop(request: Request, hub: str = HubRef, caller: Caller = Depends(require_operator)) -> StopReport:
    """Interrupt whatever holds the hub (a run, an upload) and wait for the hub to confirm."""
    return StopReport(**await find_hub(request.app.state.ctx, hub).stop(caller.label))


@router.get("/{hub}/logs", response_model=list[LogEntry])
async def list_logs(
    request: Request, hub: str = HubRef, caller: Caller = Depends(require_viewer)
) -> list[LogEntry]:
    """The run logs kept on the hub (its last runs, however they were started)."""
    actor = find_hub(request.app.state.ctx, hub)
    with hub_errors():
        runs = await actor.list_logs(who=caller.label)
    slots = int(actor.state.capabilities.get("log_slots", 10))
    return [LogEntry(index=r["index"], slot=r["index"] % slots, bytes=r["bytes"]) for r in runs]


@router.get("/{hub}/logs/{index}", response_model=LogText)
async def read_log(
    request: Request,
    hub: str = HubRef,
    index: int = Path(ge=0, le=2**31),
    caller: Caller = Depends(require_viewer),
) -> LogText:
    """One run log read from the hub, with its lines' hub time stamps."""
    actor = find_hub(request.app.state.ctx, hub)
    with hub_errors():
        parsed = await actor.read_log(index, who=caller.label)
    return LogText(
        hub_id=actor.hub_id,
        index=parsed.index,
        started_ms=parsed.started_ms,
        trigger=parsed.trigger,
        outcome=parsed.outcome,
        detail=parsed.detail,
        lines=[LogLine(line_no=ln.line_no, text=ln.text, hub_ms=ln.hub_ms) for ln in parsed.lines],
        text=parsed.text,
    )
