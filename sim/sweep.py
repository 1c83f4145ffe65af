"""One SimJob over many seeds: a local pool of contained child processes, or a Dask cluster.

    for row in sweep(SimJob("mission.py", world="wro"), parse_seeds("1-50"), workers=4):
        print(row.seed, row.result.exit, row.result.score)      # in the order the seeds finish

A run is a pure function of its job, so the seeds are independent and any engine that runs a
function somewhere gives the same per-seed results: we bring none of our own scheduling. Each seed
runs exactly as `sim run` runs it, in a child process fenced in by limits (run_process.py); the
pool only waits on children, so it is a pool of threads each minding one child process. With a
scheduler address, Dask's distributed scheduler hands the seeds to its workers, which start the
same children there; the program's text travels with each task, so a worker needs no copy of it.

The console's daemon uses sweep() too: rows come as seeds finish, so it can stream progress, and
closing the generator cancels the seeds not yet started.
"""

from __future__ import annotations

import os
import shutil
import statistics
import tempfile
import threading
from collections.abc import Iterable, Iterator
from concurrent.futures import ThreadPoolExecutor, as_completed
from dataclasses import dataclass, replace

from .fork_server import ForkServer
from .job import FINISHED, SimJob, SimResult

MAX_SEEDS = 10_000  # a bigger range is almost certainly a typo (1-50000 for 1-500)
DASK_CONNECT_TIMEOUT_S = 10.0
# Past the slowest seed's own limits (its wall-clock limit plus the runner's grace), a cluster that
# still has not answered has lost its workers: the sweep ends with an error instead of waiting.
DASK_STALL_MARGIN_S = 120.0
# A world's score is a dict; the one number a sweep summarises across seeds is the first of these.
HEADLINE_SCORES = ("points", "progress_pct")


class SweepError(ValueError):
    """Bad sweep input or an engine that cannot be reached: one line for the user."""


@dataclass
class SeedRow:
    """One seed's run: the seed and its SimResult."""

    seed: int
    result: SimResult

    def summary(self) -> dict:
        """The row `--json` prints: the keys of `sim run --json`, the program's output left out."""
        r = self.result
        return {
            "seed": self.seed,
            "score": r.score,
            "exit": r.exit,
            "sim_s": r.sim_ms / 1000,
            "pose": r.pose,
            "wall_s": r.wall_s,
            "error": r.error,
        }

    @property
    def headline(self) -> float | None:
        """The number summarised across seeds (a WRO table's points, a line track's progress)."""
        score = self.result.score or {}
        for key in HEADLINE_SCORES:
            if isinstance(score.get(key), (int, float)):
                return score[key]
        return None

    @property
    def succeeded(self) -> bool:
        """The program ran to its end: no error, reset, limit or stop."""
        return self.result.exit == FINISHED


def parse_seeds(text: str) -> list[int]:
    """ "1-50", "3", "1,4,9" or a mix ("1-5,9"): the seeds in the order given, each once."""
    items = [item.strip() for item in str(text).split(",")]
    if not any(items):
        raise SweepError("no seeds given: use a range like 1-50, one seed like 3, or a list like 1,4,9")
    seeds: dict[int, None] = {}
    for item in items:
        low, dash, high = item.partition("-")
        try:
            first, last = int(low), int(high if dash else low)
        except ValueError:
            raise SweepError(
                f"{item!r} in --seeds {text!r} is not a seed or a range: use whole numbers from 0 up, "
                "like 1-50, 3 or 1,4,9"
            ) from None
        if first < 0:
            raise SweepError(f"{item!r} in --seeds {text!r}: seeds are whole numbers from 0 up")
        if last < first:
            raise SweepError(f"--seeds {text!r}: the range {item} runs backwards; write {last}-{first}")
        if len(seeds) + (last - first + 1) > MAX_SEEDS:
            raise SweepError(
                f"--seeds {text!r} is more than {MAX_SEEDS} seeds: sweep a smaller range (or several)"
            )
        seeds.update(dict.fromkeys(range(first, last + 1)))
    return list(seeds)


def run_seed(job: dict, source: str, stop=None, forker=None) -> dict:
    """Run one job (a SimJob's dict) in a contained child process; its SimResult as a dict.

    Runs in the pool or on a Dask worker: the program's text is written to a temporary file there,
    so a worker on another machine needs no copy, and the result names the program as given.
    stop: a threading.Event that stops the run (the local pool's, when the sweep is abandoned).
    forker: the local pool's warm fork server (fork_server.py), which the child is forked from.
    """
    from dataclasses import asdict

    from .run_process import run_in_child

    sim_job = SimJob.from_dict(job)
    folder = tempfile.mkdtemp(prefix="openbricks-sweep-")
    try:
        program = os.path.join(folder, os.path.basename(sim_job.program))
        with open(program, "w", encoding="utf-8") as f:
            f.write(source)
        result, _status = run_in_child(
            replace(sim_job, program=program), quiet=True, stop=stop, forker=forker
        )
    finally:
        shutil.rmtree(folder, ignore_errors=True)
    if result.job:
        result.job["program"] = sim_job.program
    return asdict(result)


def sweep(
    template: SimJob,
    seeds: Iterable[int],
    workers: int | None = None,
    dask: str | None = None,
    source: str | None = None,
) -> Iterator[SeedRow]:
    """Run `template` once per seed; rows in the order the seeds finish.

    workers: local runs at a time (default: the machine's CPU count). dask: a scheduler address
    (tcp://host:8786) to run on instead. source: the program's text (default: read the template's
    program file). Closing the generator early cancels the seeds not yet started.
    """
    seeds = list(seeds)
    if not seeds:
        raise SweepError("no seeds to sweep")
    if template.hub_dir is not None:
        raise SweepError("a sweep's seeds each get a fresh hub flash: leave hub_dir out")
    if source is None:
        with open(template.program, encoding="utf-8") as f:
            source = f.read()
    jobs = {seed: template.with_seed(seed).to_dict() for seed in seeds}
    if dask:
        yield from _on_dask(dask, jobs, source, template)
    else:
        yield from _on_pool(workers or os.cpu_count() or 1, jobs, source)


def _on_pool(workers: int, jobs: dict, source: str) -> Iterator[SeedRow]:
    """Threads that each mind one contained child at a time, forked from one warm fork server (the
    imports paid once, not once per seed) where the OS can fork: the user's shared one if it runs
    (shared_server.py; a `sim run` left it), else one of the sweep's own, started meanwhile. Abandoned
    (Ctrl-C, a stopped job), seeds not started are dropped and running ones stopped, so no seed
    outlives the sweep."""
    from . import shared_server

    stop = threading.Event()
    forker = shared_server.connect() or (ForkServer() if hasattr(os, "fork") else None)
    pool = ThreadPoolExecutor(max_workers=workers, thread_name_prefix="sweep")
    try:
        futures = {pool.submit(run_seed, job, source, stop, forker): seed for seed, job in jobs.items()}
        for future in as_completed(futures):
            yield SeedRow(futures[future], SimResult(**future.result()))
    finally:
        stop.set()
        pool.shutdown(wait=True, cancel_futures=True)
        if forker is not None:
            forker.close()  # a private server ends with it; the shared one stays for the runs after


def _on_dask(address: str, jobs: dict, source: str, template: SimJob) -> Iterator[SeedRow]:
    try:
        from distributed import Client
        from distributed import as_completed as dask_completed
    except ImportError as exc:
        raise SweepError(
            f"--dask needs Dask's distributed scheduler client ({exc}): pip install 'openbricks[sim]'"
        ) from None
    _probe(address)
    try:
        client = Client(address, timeout=DASK_CONNECT_TIMEOUT_S, set_as_default=False)
    except Exception as exc:  # noqa: BLE001 - whatever went wrong, the user gets one line
        raise SweepError(f"cannot use the Dask scheduler at {address}: {exc}") from None
    try:
        source_future = client.scatter(source, broadcast=True)
        futures = {
            client.submit(run_seed, job, source_future, pure=False): seed for seed, job in jobs.items()
        }
        stall_s = (template.wall_limit() or template.limit_ms / 1000) + DASK_STALL_MARGIN_S
        try:
            for future in dask_completed(futures, loop=client.loop, timeout=stall_s * len(futures)):
                yield SeedRow(futures[future], SimResult(**future.result()))
        except TimeoutError:
            raise SweepError(
                f"the Dask cluster at {address} stopped answering: no result within {stall_s:g} s per seed"
            ) from None
        finally:  # seeds not started are dropped; a running one ends within its own limits
            client.cancel(list(futures))
    finally:
        client.close()


def _probe(address: str) -> None:
    """Shake hands with the scheduler before a Client is built: a Client that fails to connect
    lingers and spends another two timeouts closing, and something else listening at the address
    (a web server on the wrong port) makes Dask's handshake read nonsense."""
    import asyncio

    from distributed.comm import connect

    async def handshake():
        comm = await connect(address, timeout=DASK_CONNECT_TIMEOUT_S)
        await comm.close()

    scheme, _, where = address.partition("://") if "://" in address else ("tcp", "", address)
    host, _, port = where.rpartition(":")
    if scheme not in ("tcp", "tls") or not host or not port.isdigit():
        raise SweepError(
            f"--dask {address!r}: give the scheduler's address as tcp://HOST:PORT, e.g. tcp://10.0.0.5:8786"
        )
    try:
        asyncio.run(handshake())
    except MemoryError:  # the "message length" it read was someone else's bytes
        raise SweepError(
            f"something other than a Dask scheduler answered at {address}: check the port (a scheduler "
            "listens on 8786 unless told otherwise)"
        ) from None
    except Exception as exc:  # noqa: BLE001 - refused, timed out, or not Dask at all
        reason = str(exc).splitlines()[0] if str(exc) else type(exc).__name__
        raise SweepError(
            f"cannot reach the Dask scheduler at {address} within {DASK_CONNECT_TIMEOUT_S:g} s ({reason}): "
            "is `dask scheduler` running there, and is the address tcp://HOST:PORT?"
        ) from None


def summarise(rows: list[SeedRow]) -> dict:
    """Mean, median and lowest score over the seeds that have one; the share that ran to the end."""
    scores = [row.headline for row in rows if row.headline is not None]
    return {
        "seeds": len(rows),
        "score_key": next(
            (key for key in HEADLINE_SCORES if any(key in (r.result.score or {}) for r in rows)), None
        ),
        "mean_score": round(statistics.fmean(scores), 3) if scores else None,
        "median_score": statistics.median(scores) if scores else None,
        "min_score": min(scores) if scores else None,
        "success_rate": round(sum(row.succeeded for row in rows) / len(rows), 4) if rows else None,
    }
