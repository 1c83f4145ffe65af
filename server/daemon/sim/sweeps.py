"""Seed sweeps as console jobs: `openbricks sim sweep`'s engine (openbricks_sim.sweep, a local pool of
contained child processes or a Dask cluster) run by the job registry, each finished seed a step and a
progress event, the rows and their summary the job's result.

The sweep's generator blocks while seeds run, so it is driven from one worker thread, which also
closes it; a stop request is honoured as the next seed finishes (the seeds running then end within
their own limits). The program is the stored one, sent as text to every seed.
"""

from __future__ import annotations

import asyncio
import io
import threading

from openbricks_server.daemon.jobs.registry import Job, JobFailed, JobRegistry
from openbricks_sim.job import SimJob, SimResult
from openbricks_sim.sweep import SeedRow, SweepError, summarise, sweep
from openbricks_sim.sweep_report import write_csv_to

KIND = "sim_sweep"


class SweepJobs:
    def __init__(self, jobs: JobRegistry):
        self.jobs = jobs
        self._stops: dict[str, threading.Event] = {}

    def start(
        self,
        template: SimJob,
        seeds: list[int],
        source: str,
        version: int,
        workers,
        dask,
        who: str,
        world_label: str | None = None,
    ) -> Job:
        # The program's stored version is kept, so one seed can be run again exactly as the sweep ran it;
        # an uploaded world is kept by its name (what a run is started with), not its file's path.
        params = {**template.to_dict(), "version": version, "seeds": seeds, "workers": workers, "dask": dask}
        if world_label is not None:
            params["world"] = world_label
        job = self.jobs.create(KIND, template.program, who, params)
        stop = self._stops[job.job_id] = threading.Event()

        async def work(job: Job) -> dict:
            self.jobs.running(job)
            loop = asyncio.get_running_loop()

            def finished(row: SeedRow, done: int) -> None:
                score = "" if row.headline is None else f", score {row.headline:g}"
                self.jobs.step(job, f"seed {row.seed}: {row.result.exit}{score} ({done}/{len(seeds)})")
                self.jobs.progress(job, 100.0 * done / len(seeds))

            def drive() -> list[SeedRow]:
                rows: list[SeedRow] = []
                runs = sweep(template, seeds, workers=workers, dask=dask, source=source)
                try:
                    for row in runs:
                        rows.append(row)
                        loop.call_soon_threadsafe(finished, row, len(rows))
                        if stop.is_set():
                            break
                finally:
                    runs.close()  # seeds not started are dropped, running ones stopped
                return rows

            try:
                rows = await asyncio.to_thread(drive)
            except SweepError as exc:
                raise JobFailed(str(exc)) from None
            finally:
                self._stops.pop(job.job_id, None)
            if stop.is_set() and len(rows) < len(seeds):
                raise JobFailed(f"stopped after {len(rows)} of {len(seeds)} seeds")
            rows.sort(key=lambda row: row.seed)
            return {"rows": [row.summary() for row in rows], "summary": summarise(rows)}

        self.jobs.start(job, work)
        return job

    def stop(self, job_id: str) -> bool:
        """Ask a running sweep to end as its next seed finishes; False when it is not running."""
        stop = self._stops.get(job_id)
        if stop is None:
            return False
        stop.set()
        return True


def rows_csv(result: dict) -> str:
    """A finished sweep's rows as `sim sweep --csv` writes them."""
    rows = [
        SeedRow(
            row["seed"],
            SimResult(
                exit=row["exit"],
                sim_ms=round(row["sim_s"] * 1000),
                wall_s=row["wall_s"],
                pose=row["pose"],
                output="",
                error=row["error"],
                score=row["score"],
            ),
        )
        for row in result["rows"]
    ]
    out = io.StringIO()
    write_csv_to(out, rows)
    return out.getvalue()
