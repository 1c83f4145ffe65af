"""Seed sweeps: one stored program over many seeds (`openbricks sim sweep` through the console), on a
local pool of contained child processes or a Dask cluster; followed as a job (`job` events, a step
per seed), read back as rows with their summary, or as the CSV the command writes."""

from __future__ import annotations

from fastapi import APIRouter, Depends, Query, Request
from fastapi.responses import Response
from pydantic import BaseModel, Field

from openbricks_server.daemon.auth import Caller, audit_as_started, require_operator, require_viewer
from openbricks_server.daemon.competition import unlocked
from openbricks_server.daemon.errors import ApiError
from openbricks_server.daemon.programs import check_name
from openbricks_server.daemon.routers.jobs import JobOut, JobRef, WaitQuery, find_job, registry
from openbricks_server.daemon.routers.sim import WORLDS, Chassis, resolve_world
from openbricks_server.daemon.sim.sweeps import KIND, rows_csv
from openbricks_sim.job import JobError, SimJob
from openbricks_sim.sweep import SweepError, parse_seeds

router = APIRouter(prefix="/sim/sweeps", tags=["sim"], dependencies=[Depends(require_viewer)])

MAX_WORKERS = 16
START_ALLOWED = Depends(unlocked("start a sweep"))  # operators, unless competition mode locks it


class SweepRequest(BaseModel):
    program: str = Field(min_length=1, max_length=200, description="a stored program's name, e.g. square.py")
    version: int | None = Field(None, ge=1, description="the stored version (default: the newest)")
    world: str = Field(
        "empty", max_length=200, description=f"one of: {', '.join(WORLDS)}, or an uploaded world's name"
    )
    chassis: Chassis | None = Field(None, description="default: the build whose motors the program makes")
    seeds: str = Field(
        min_length=1, max_length=200, description="a range (1-50), one seed (3) or a list (1,4,9), as the CLI"
    )
    workers: int | None = Field(
        None, ge=1, le=MAX_WORKERS, description="local runs at a time (default: one per CPU)"
    )
    dask: str | None = Field(
        None, max_length=200, description="a Dask scheduler to run on instead, tcp://HOST:PORT"
    )
    limit_ms: int = Field(60_000, ge=1, le=3_600_000, description="simulated time each seed may take")
    memory_mb: int = Field(1024, ge=256, le=8192, description="each seed's process's address-space limit")


def _sweeps(request: Request):
    sweeps = request.app.state.ctx.sweeps
    if sweeps is None:
        raise ApiError(503, "jobs_unavailable", "the job registry is not running", "restart the console")
    return sweeps


@router.post("", response_model=JobOut, status_code=202)
async def start_sweep(request: Request, body: SweepRequest, caller: Caller = START_ALLOWED) -> JobOut:
    """Start the sweep and answer at once with its job; `GET /api/sim/sweeps/{job}?wait_s=` waits for
    the rows. Every seed runs as `sim run` runs it: its own child process, with its limits."""
    world = resolve_world(request, body.world)
    if body.workers is not None and body.dask is not None:
        raise ApiError.invalid(
            "bad_sweep", "give workers or dask, not both", "workers is for the local pool only"
        )
    try:
        seeds = parse_seeds(body.seeds)
    except SweepError as exc:
        raise ApiError.invalid(
            "bad_seeds", str(exc).replace("--seeds", "seeds"), "e.g. 1-50, 3 or 1,4,9"
        ) from None
    ctx = request.app.state.ctx
    name = check_name(body.program)
    found = ctx.store.programs.version(name, body.version)
    if found is None:
        raise ApiError.not_found(
            f"program {name!r}", "save it first (PUT /api/programs/NAME); GET /api/programs lists them"
        )
    try:
        template = SimJob(
            found["name"],
            world=world,
            chassis=body.chassis,
            limit_ms=body.limit_ms,
            memory_mb=body.memory_mb,
        )
    except JobError as exc:
        raise ApiError.invalid("bad_sweep", str(exc), "see the fields of POST /api/sim/sweeps") from None
    job = _sweeps(request).start(
        template,
        seeds,
        found["source"],
        found["version"],
        body.workers,
        body.dask,
        caller.label,
        world_label=body.world if world != body.world else None,
    )
    audit_as_started(request)
    return JobOut(**job.record())


@router.get("", response_model=list[JobOut])
async def list_sweeps(request: Request, limit: int = Query(50, ge=1, le=1000)) -> list[JobOut]:
    """Sweeps, the most recent first."""
    return [JobOut(**job) for job in registry(request).list(KIND, None, limit)]


@router.get("/{job}", response_model=JobOut)
async def get_sweep(request: Request, job: str = JobRef, wait_s: float = WaitQuery) -> JobOut:
    """A sweep: its progress and a step per finished seed; once done, `result.rows` (one per seed: seed,
    score, exit, sim_s, pose, as `sim run --json`) and `result.summary`."""
    return await find_job(request, job, KIND, wait_s)


@router.post("/{job}/stop", response_model=JobOut)
async def stop_sweep(
    request: Request, job: str = JobRef, _caller: Caller = Depends(require_operator)
) -> JobOut:
    """End the sweep as its next seed finishes (seeds not started are dropped)."""
    found = await find_job(request, job, KIND, 0)
    _sweeps(request).stop(found.job_id)
    return await find_job(request, job, KIND, 0)


@router.get(
    "/{job}/rows.csv",
    response_class=Response,
    responses={200: {"content": {"text/csv": {}}, "description": "one line per seed"}},
)
async def sweep_csv(request: Request, job: str = JobRef) -> Response:
    """A finished sweep's rows as `openbricks sim sweep --csv` writes them."""
    found = await find_job(request, job, KIND, 0)
    if found.result is None:
        raise ApiError.conflict(
            "sweep_not_done",
            f"sweep {found.job_id} is {found.state}: it has no rows yet",
            f"wait for it: GET /api/sim/sweeps/{found.job_id}?wait_s=60",
        )
    return Response(
        rows_csv(found.result),
        media_type="text/csv",
        headers={"content-disposition": f'attachment; filename="sweep-{found.job_id}.csv"'},
    )
