"""Simulator runs: start one (a child process, never the daemon), steer it, read it back, download its
recording. Each run is also in `/api/runs` (hub "sim", origin "sim") with its output and telemetry."""

from __future__ import annotations

import math
import re
from typing import Literal

from fastapi import APIRouter, Depends, Query, Request
from fastapi.responses import FileResponse
from pydantic import BaseModel, Field, field_validator

from openbricks_server.daemon.auth import Caller, require_operator, require_viewer
from openbricks_server.daemon.competition import unlocked
from openbricks_server.daemon.errors import ApiError
from openbricks_server.daemon.programs import check_name
from openbricks_server.daemon.sim.worlds import MAX_UPLOAD_BYTES, WorldStore, WorldUploadError
from openbricks_sim.job import CHASSIS_NAMES, WORLD_NAMES

router = APIRouter(prefix="/sim", tags=["sim"], dependencies=[Depends(require_viewer)])

WORLDS = tuple(name.strip() for name in WORLD_NAMES.split(","))
_ULID = re.compile(r"^[0-9A-HJKMNP-TV-Z]{26}$")
JobState = Literal["queued", "running", "done", "failed", "cancelled"]
Chassis = Literal[CHASSIS_NAMES]  # type: ignore[valid-type]
MAX_SPEED = 64.0
START_ALLOWED = Depends(unlocked("start a sim run"))  # operators, unless competition mode locks it


class StartPose(BaseModel):
    x_mm: float = Field(ge=-10_000, le=10_000)
    y_mm: float = Field(ge=-10_000, le=10_000)
    heading_deg: float = Field(0.0, ge=-3600, le=3600, description="clockwise from +x")


class SimRunRequest(BaseModel):
    program: str = Field(min_length=1, max_length=200, description="a stored program's name, e.g. square.py")
    version: int | None = Field(None, ge=1, description="the stored version (default: the newest)")
    world: str = Field(
        "empty", max_length=200, description=f"one of: {', '.join(WORLDS)}, or an uploaded world's name"
    )
    chassis: Chassis | None = Field(None, description="default: the build whose motors the program makes")
    seed: int = Field(0, ge=0, le=2**31 - 1)
    start: StartPose | None = Field(None, description="default: the world's start")
    speed: float | None = Field(
        1.0, gt=0, le=MAX_SPEED, description="real-time factor; null: as fast as possible"
    )
    limit_ms: int = Field(60_000, ge=1, le=3_600_000, description="simulated time the run may take")
    wall_limit_s: float | None = Field(
        None,
        gt=0,
        le=86_400,
        description="wall-clock time the run may take, paused or not (default: from limit_ms and speed)",
    )
    memory_mb: int = Field(1024, ge=256, le=8192, description="the run's process's address-space limit")


class SpeedRequest(BaseModel):
    speed: float | None = Field(gt=0, le=MAX_SPEED, description="real-time factor; null: as fast as possible")

    @field_validator("speed")
    @classmethod
    def _finite(cls, value):
        if value is not None and not math.isfinite(value):
            raise ValueError("give a finite speed")
        return value


class SimResult(BaseModel):
    exit: str
    sim_ms: int | None
    pose: dict[str, float] | None
    score: dict | None


class SimRun(BaseModel):
    """A sim run: the Job the console pages follow (job_id, kind, state, progress, label, message,
    result) and what only a sim run has."""

    run_id: str
    job_id: str
    kind: Literal["sim"]
    state: JobState
    progress: float | None
    label: str | None
    message: str | None
    result: SimResult | None
    program_name: str | None
    program_sha256: str | None
    who: str | None
    world: str
    chassis: str | None
    seed: int
    start_mm_deg: list[float] | None
    speed: float | None
    limit_ms: int
    wall_limit_s: float
    memory_mb: int
    started_ms: int
    ended_ms: int | None
    exit: str | None
    sim_ms: int
    pose: dict[str, float] | None
    score: dict | None
    error: str | None
    live: bool  # its process runs (its view can be watched; it can be paused, sped up, stopped)
    paused: bool
    view_url: str
    replay_url: str | None
    recording_url: str | None


class World(BaseModel):
    name: str
    description: str = ""
    uploaded: bool = False  # a team's world (POST /api/sim/worlds), not a built-in one
    size_mm: list[float] | None = None
    props: int | None = None
    zones: int | None = None


def world_store(request: Request) -> WorldStore:
    return WorldStore(request.app.state.ctx.config.resolved_data_dir / "worlds")


def resolve_world(request: Request, name: str) -> str:
    """What a run's child builds for a world name: a built-in alias as it is, an uploaded world's name
    as its world file's path. Refuses any other name with the list of worlds."""
    if name in WORLDS:
        return name
    path = world_store(request).path(name)
    if path is None:
        uploaded = [w["name"] for w in world_store(request).list()]
        raise ApiError.invalid(
            "unknown_world",
            f"unknown world {name!r}",
            f"use one of: {', '.join([*WORLDS, *uploaded])} (GET /api/sim/worlds), or upload yours "
            "(POST /api/sim/worlds)",
        )
    return str(path)


def _jobs(request: Request):
    return request.app.state.ctx.sim


def _check_id(run_id: str) -> str:
    if not _ULID.fullmatch(run_id):
        raise ApiError.invalid(
            "bad_run_id",
            f"{run_id[:40]!r} is not a run id",
            "run ids are 26 characters, e.g. from GET /api/sim/runs",
        )
    return run_id


def _view(request: Request, run_id: str) -> SimRun:
    found = _jobs(request).view(_check_id(run_id))
    if found is None:
        raise ApiError.not_found(f"sim run {run_id}", "GET /api/sim/runs lists the sim runs")
    return SimRun(**found)


def _live(request: Request, run_id: str, action: str):
    run = _view(request, run_id)
    job = _jobs(request).live.get(run_id)
    if job is None:
        raise ApiError.conflict(
            "sim_run_ended",
            f"sim run {run_id} has ended ({run.exit or run.state}): there is nothing to {action}",
            "start a new run with POST /api/sim/runs, or watch this one again at its replay_url",
        )
    if not job.ready.is_set():
        raise ApiError.conflict(
            "sim_run_starting",
            f"sim run {run_id} is still starting (the simulator loads the world): it cannot {action} yet",
            "try again in a moment (its job event says when it runs), or stop it",
        )
    return job


@router.get("/worlds", response_model=list[World])
async def list_worlds(request: Request) -> list[World]:
    """The worlds a sim run can use: the built-in ones, then those uploaded to this console."""
    return [World(name=name) for name in WORLDS] + [World(**w) for w in world_store(request).list()]


@router.post(
    "/worlds",
    response_model=World,
    status_code=201,
    openapi_extra={
        "requestBody": {
            "required": True,
            "content": {"application/octet-stream": {"schema": {"type": "string", "format": "binary"}}},
        }
    },
)
async def upload_world(request: Request, _caller: Caller = Depends(require_operator)) -> World:
    """Upload a world: the request body is a zip of its world file (.toml) and the mat image it names.
    It is checked whole (422 `bad_world` lists every problem of the file, each with its line) and kept
    in the console's data folder under the world's name, replacing an older upload of that name."""
    data = bytearray()
    async for chunk in request.stream():
        data += chunk
        if len(data) > MAX_UPLOAD_BYTES:
            raise ApiError(
                413,
                "too_large",
                f"the world is larger than {MAX_UPLOAD_BYTES // 2**20} MB",
                "shrink the mat image",
            )
    if not data:
        raise ApiError.invalid("empty", "the request body is empty: send a zip of the world file and its mat")
    try:
        saved = world_store(request).save_zip(bytes(data))
    except WorldUploadError as exc:
        raise ApiError.invalid(
            "bad_world",
            "; ".join(exc.problems),
            "fix the world file (the manual's \"Your season's table\" page) and upload it again",
            detail={"problems": exc.problems},
        ) from None
    return World(**saved)


@router.post("/runs", response_model=SimRun, status_code=201)
async def start_run(request: Request, body: SimRunRequest, caller: Caller = START_ALLOWED) -> SimRun:
    """Start a stored program in the simulator: a child process with time and memory limits, its 3D
    view at `view_url`, its output and telemetry on the event stream."""
    world = resolve_world(request, body.world)
    ctx = request.app.state.ctx
    name = check_name(body.program)
    found = ctx.store.programs.version(name, body.version)
    if found is None:
        what = f"program {name!r}" + (f" version {body.version}" if body.version else "")
        raise ApiError.not_found(what, "save it first (PUT /api/programs/NAME); GET /api/programs lists them")
    jobs = _jobs(request)
    if len(jobs.live) >= jobs.max_live:
        raise ApiError.conflict(
            "sim_busy",
            f"{len(jobs.live)} sim runs are going already, the most this console runs at once",
            "wait for one to end, or stop one (POST /api/sim/runs/{id}/stop)",
            detail={"live": sorted(jobs.live)},
        )
    start = body.start
    try:
        run_id = await jobs.start(
            program_name=found["name"],
            source=found["source"],
            world=world,
            chassis=body.chassis,
            seed=body.seed,
            start_mm_deg=None if start is None else [start.x_mm, start.y_mm, start.heading_deg],
            speed=body.speed,
            limit_ms=body.limit_ms,
            wall_limit_s=body.wall_limit_s,
            memory_mb=body.memory_mb,
            who=caller.label,
        )
    except OSError as exc:
        raise ApiError(500, "sim_start_failed", f"the simulator could not be started: {exc}") from None
    if world != body.world:  # an uploaded world: the history names it, not its file's path
        ctx.store.sim_runs.update(run_id, world=body.world)
    return _view(request, run_id)


@router.get("/runs", response_model=list[SimRun])
async def list_runs(
    request: Request,
    before: str | None = Query(None, description="a run id: only older runs (paging)"),
    limit: int = Query(50, ge=1, le=1000),
) -> list[SimRun]:
    """Sim runs newest first, with world, seed, state, score and where to watch or replay them."""
    if before is not None:
        _check_id(before)
    rows = request.app.state.ctx.store.sim_runs.list(before, limit)
    return [_view(request, row["run_id"]) for row in rows]


@router.get("/runs/{run_id}", response_model=SimRun)
async def get_run(request: Request, run_id: str) -> SimRun:
    return _view(request, run_id)


@router.post("/runs/{run_id}/pause", response_model=SimRun)
async def pause_run(request: Request, run_id: str, _caller: Caller = Depends(require_operator)) -> SimRun:
    """Hold simulated time (the wall-clock limit goes on counting)."""
    _live(request, run_id, "pause").send({"cmd": "pause"})
    return await _after_control(request, run_id)


@router.post("/runs/{run_id}/resume", response_model=SimRun)
async def resume_run(request: Request, run_id: str, _caller: Caller = Depends(require_operator)) -> SimRun:
    _live(request, run_id, "resume").send({"cmd": "resume"})
    return await _after_control(request, run_id)


@router.post("/runs/{run_id}/speed", response_model=SimRun)
async def set_speed(
    request: Request, run_id: str, body: SpeedRequest, _caller: Caller = Depends(require_operator)
) -> SimRun:
    """Change the real-time factor (null: as fast as possible)."""
    _live(request, run_id, "change speed").send({"cmd": "speed", "speed": body.speed})
    return await _after_control(request, run_id)


@router.post("/runs/{run_id}/stop", response_model=SimRun)
async def stop_run(request: Request, run_id: str, _caller: Caller = Depends(require_operator)) -> SimRun:
    """Stop the run (its process is killed if it does not end within seconds) and answer how it ended."""
    run = _view(request, run_id)
    job = _jobs(request).live.get(run_id)
    if job is not None:
        await job.stop()
        return _view(request, run_id)
    return run


async def _after_control(request: Request, run_id: str) -> SimRun:
    """The run once the child has applied a control (it answers with a state event), briefly waited for."""
    job = _jobs(request).live.get(run_id)
    if job is not None:
        await job.acknowledged(timeout_s=2.0)
    return _view(request, run_id)


@router.get(
    "/runs/{run_id}/recording",
    response_class=FileResponse,
    responses={
        200: {"content": {"application/octet-stream": {}}, "description": "the run's .viser recording"}
    },
)
async def get_recording(request: Request, run_id: str):
    """The run's 3D recording (a `.viser` file viser's client plays back with a timeline)."""
    run = _view(request, run_id)
    ctx = request.app.state.ctx
    row = ctx.store.sim_runs.get(run_id)
    if row["recording"] is None:
        if run.live:
            raise ApiError.conflict(
                "sim_run_live",
                f"sim run {run_id} is still going: its recording is written when it ends",
                "watch it live at its view_url meanwhile",
            )
        raise ApiError.not_found(
            f"a recording of sim run {run_id}", "this run ended before its recording could be written"
        )
    path = ctx.sim.data_dir / row["recording"]
    if not path.is_file():
        raise ApiError.not_found(
            f"the recording file of sim run {run_id}", "it was removed from the data dir"
        )
    return FileResponse(
        path,
        media_type="application/octet-stream",
        filename=f"{run_id}.viser",
        headers={"cache-control": "no-cache"},
    )
