"""The job registry: every job gets an id, a kind, a label (what it works on: a port, a hub), a state,
steps, progress and a result; every change is stored and published as a `job` event (progress as
`job_progress`, only when the whole percent changes) so any client can follow it live or look it up later.

A job's work is a coroutine given its `Job`; what it returns is the result. A `CliError` (the message a
user reads, shared with the CLI), a hub's refusal or a `JobFailed` fails the job with that message;
anything else fails it as an unexpected error (logged). `start` runs a job in the background (flash:
the request answers at once); `run` runs it to its end in the caller (a servo scan answers with its
result). At shutdown, jobs still running are cancelled and marked so.
"""

from __future__ import annotations

import asyncio
import contextlib
import logging
from collections.abc import Awaitable, Callable
from dataclasses import asdict, dataclass, field
from typing import Literal

from ulid import ULID

from openbricks_server.daemon.events import EventBus
from openbricks_server.daemon.hubs.errors import HubOperationError
from openbricks_server.daemon.store import Store, now_ms
from openbricks_server.errors import CliError

log = logging.getLogger("openbricks.console")

JobState = Literal["queued", "running", "done", "failed", "cancelled"]
FINISHED: frozenset[str] = frozenset({"done", "failed", "cancelled"})
MAX_STEPS = 200  # step lines kept per job
# A finished job's audit entry, in the audit log's HTTP-like statuses: 200 done, 4xx/5xx failed.
JOB_AUDIT_STATUS = {"done": 200, "failed": 500, "cancelled": 503}


class JobFailed(Exception):
    """The job cannot go on; the message says why and what to do."""


@dataclass
class Job:
    job_id: str
    kind: str
    label: str
    who: str
    params: dict
    batch: str | None = None
    state: JobState = "queued"
    progress: float | None = None
    message: str | None = None
    result: dict | None = None
    steps: list[str] = field(default_factory=list)
    created_ms: int = field(default_factory=now_ms)
    started_ms: int | None = None
    ended_ms: int | None = None

    def record(self) -> dict:
        return asdict(self)


class JobRegistry:
    def __init__(self, store: Store, events: EventBus):
        self.store = store
        self.events = events
        self._live: dict[str, Job] = {}
        self._tasks: dict[str, asyncio.Task] = {}
        self._finished: dict[str, asyncio.Event] = {}

    # -- creating and running -------------------------------------------------------------------------

    def create(self, kind: str, label: str, who: str, params: dict, batch: str | None = None) -> Job:
        job = Job(str(ULID()), kind, label, who, params, batch)
        self._live[job.job_id] = job
        self._finished[job.job_id] = asyncio.Event()
        self._changed(job)
        return job

    def start(self, job: Job, work: Callable[[Job], Awaitable[dict]]) -> asyncio.Task:
        task = asyncio.create_task(self._run(job, work), name=f"job {job.kind} {job.label}")
        self._tasks[job.job_id] = task
        return task

    async def _run(self, job: Job, work: Callable[[Job], Awaitable[dict]]) -> None:
        try:
            await self.run(job, work)
        except Exception:  # noqa: BLE001 - recorded on the job; nobody awaits a started job's task
            pass
        finally:
            self._tasks.pop(job.job_id, None)

    async def run(self, job: Job, work: Callable[[Job], Awaitable[dict]]) -> dict:
        """Run `work(job)` to its end here, recording how it ended; its exception is raised again."""
        try:
            result = await work(job)
        except asyncio.CancelledError:
            self._end(job, "cancelled", "cancelled: the console was shut down while it ran")
            raise
        except (CliError, JobFailed) as exc:
            self._end(job, "failed", str(exc))
            raise
        except HubOperationError as exc:  # the hub refused (busy, offline ...) or its link failed
            self._end(job, "failed", f"{exc.message}; {exc.hint}" if exc.hint else exc.message)
            raise
        except Exception as exc:
            log.exception("job %s (%s %s) failed unexpectedly", job.job_id, job.kind, job.label)
            self._end(job, "failed", f"unexpected error ({type(exc).__name__}: {exc}); see the console's log")
            raise
        job.result = result
        self._end(job, "done", None)
        return result

    def running(self, job: Job) -> None:
        job.state = "running"
        job.started_ms = now_ms()
        self._changed(job)

    def step(self, job: Job, text: str) -> None:
        if len(job.steps) < MAX_STEPS:
            job.steps.append(text)
        job.message = text
        self._changed(job)

    def progress(self, job: Job, percent: float) -> None:
        percent = max(0.0, min(100.0, float(percent)))
        if job.progress is not None and int(percent) == int(job.progress):
            job.progress = percent
            return
        job.progress = percent
        self.store.jobs.save(job.record())
        self.events.publish("job_progress", self._summary(job))

    def _end(self, job: Job, state: JobState, message: str | None) -> None:
        job.state = state
        job.ended_ms = now_ms()
        if message is not None:
            job.message = message
        elif state == "done":
            job.message = "done"
        self._changed(job)
        # Only an operator's request starts a job; its entry said "started", this one says how it ended.
        self.store.audit.add(job.who, "operator", f"{job.kind} {job.label}", JOB_AUDIT_STATUS[state])
        self._live.pop(job.job_id, None)
        self._finished.pop(job.job_id).set()

    def _changed(self, job: Job) -> None:
        self.store.jobs.save(job.record())
        self.events.publish("job", job.record())

    @staticmethod
    def _summary(job: Job) -> dict:
        return {
            "job_id": job.job_id,
            "kind": job.kind,
            "label": job.label,
            "batch": job.batch,
            "state": job.state,
            "progress": job.progress,
        }

    # -- reading ----------------------------------------------------------------------------------------

    def get(self, job_id: str) -> dict | None:
        live = self._live.get(job_id)
        return live.record() if live is not None else self.store.jobs.get(job_id)

    def list(
        self,
        kind: str | None = None,
        batch: str | None = None,
        limit: int = 100,
        before: str | None = None,
        state: str | None = None,
    ) -> list[dict]:
        return self.store.jobs.list(kind, batch, limit, before, state)

    def active(self, kind: str | None = None) -> list[Job]:
        return [job for job in self._live.values() if kind is None or job.kind == kind]

    async def wait(self, job_id: str, timeout_s: float) -> None:
        """Until the job has finished or `timeout_s` passed (whichever first)."""
        finished = self._finished.get(job_id)
        if finished is None:
            return
        with contextlib.suppress(TimeoutError):
            async with asyncio.timeout(timeout_s):
                await finished.wait()

    async def close(self) -> None:
        tasks = list(self._tasks.values())
        for task in tasks:
            task.cancel()
        await asyncio.gather(*tasks, return_exceptions=True)
