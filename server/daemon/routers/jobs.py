"""Jobs of every kind (flash, servo scans and re-IDs, ...): the recent ones, and one by id, optionally
waiting for it to finish. The routers that start jobs (flash, servos) answer with the same `JobOut`."""

from __future__ import annotations

import re

from fastapi import APIRouter, Depends, Path, Query, Request
from pydantic import BaseModel

from openbricks_server.daemon.auth import require_viewer
from openbricks_server.daemon.errors import ApiError
from openbricks_server.daemon.jobs.registry import JobState

router = APIRouter(prefix="/jobs", tags=["jobs"], dependencies=[Depends(require_viewer)])

_ULID = re.compile(r"^[0-9A-HJKMNP-TV-Z]{26}$")
MAX_WAIT_S = 600.0
_LISTINGS = {"flash": "GET /api/flash", "sim_sweep": "GET /api/sim/sweeps"}
JobRef = Path(description="the job's id, as POST answered it", max_length=40)
WaitQuery = Query(
    0.0,
    ge=0,
    le=MAX_WAIT_S,
    description="wait up to this many seconds for the job to end",
)


class JobOut(BaseModel):
    job_id: str
    kind: str  # flash, servo_scan, servo_set_id
    label: str  # what it works on: a port, a hub
    batch: str | None  # the jobs started by one request share it
    who: str
    state: str  # queued, running, done, failed, cancelled
    progress: float | None  # percent, for jobs that report it
    message: str | None  # the latest step; once failed, why
    params: dict
    result: dict | None  # once done
    steps: list[str]
    created_ms: int
    started_ms: int | None
    ended_ms: int | None


def registry(request: Request):
    jobs = request.app.state.ctx.jobs
    if jobs is None:
        raise ApiError(503, "jobs_unavailable", "the job registry is not running", "restart the console")
    return jobs


async def find_job(request: Request, job_id: str, kind: str | None, wait_s: float) -> JobOut:
    jobs = registry(request)
    found = jobs.get(job_id) if _ULID.match(job_id) else None
    if found is None or (kind is not None and found["kind"] != kind):
        listing = _LISTINGS.get(kind, "GET /api/jobs")
        raise ApiError.not_found(f"job {job_id!r}", f"{listing} lists the recent ones")
    if wait_s > 0:
        await jobs.wait(job_id, wait_s)
        found = jobs.get(job_id)
    return JobOut(**found)


@router.get("", response_model=list[JobOut])
async def list_jobs(
    request: Request,
    kind: str | None = Query(None, max_length=40, description="only jobs of this kind"),
    batch: str | None = Query(None, max_length=40, description="only the jobs one request started"),
    state: JobState | None = Query(None, description="only jobs in this state"),
    before: str | None = Query(None, max_length=40, description="a job id: only older jobs (paging)"),
    limit: int = Query(100, ge=1, le=1000),
) -> list[JobOut]:
    """The most recent jobs first (the History page's Jobs list)."""
    return [JobOut(**job) for job in registry(request).list(kind, batch, limit, before, state)]


@router.get("/{job}", response_model=JobOut)
async def get_job(request: Request, job: str = JobRef, wait_s: float = WaitQuery) -> JobOut:
    return await find_job(request, job, None, wait_s)
