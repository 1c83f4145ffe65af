"""Seed sweeps: how many seeds a minute the local pool and a Dask cluster get through, and what one
sim job costs before its program does anything.

- start latency: a SimJob whose program is empty, run the way `sim run` and every seed run it (a
  contained child process: interpreter start, imports, the world's build, the limits, the result
  back over a pipe). The median of a few runs, for the empty world and for the WRO table.
- throughput: the same SEEDS seeds of a short drive across the WRO table (3 s simulated), on the
  local pool with 2 workers (its children forked from one warm fork server: its own, started
  within the timed sweep, then the user's shared one that a `sim run` leaves running), then on a Dask
  LocalCluster of 2 worker processes on 127.0.0.1 (its start-up timed apart, as a standing cluster
  would not pay it per sweep);
- the pool against one warm run at a time: WARM_RUNS seeds one after another from a warm fork server
  give one warm run's rate, and the pool's throughput over WORKERS x that rate says how much of the
  cores the sweep keeps busy (bar: >= 0.9).

Every figure carries the 1-minute load average when it was taken: on a shared machine the load,
not the engine, is often what moves them.
"""

from __future__ import annotations

import contextlib
import os
import signal
import statistics
import tempfile
import time

from benchmarks import Row

SEEDS = 50
WORKERS = 2
WARM_RUNS = 10
LATENCY_RUNS = 5


def _load() -> str:
    return f"load {os.getloadavg()[0]:.1f}"


def _start_latency(folder: str, world: str) -> Row:
    from openbricks_sim.job import SimJob
    from openbricks_sim.run_process import run_in_child

    program = os.path.join(folder, "empty.py")
    with open(program, "w") as f:
        f.write("pass\n")
    times = []
    for _ in range(LATENCY_RUNS):
        started = time.perf_counter()
        result, _ = run_in_child(SimJob(program, world=world), quiet=True)
        times.append(time.perf_counter() - started)
        assert result.exit == "finished", result.error
    return Row(
        f"start latency, {world} world",
        statistics.median(times) * 1000,
        "ms",
        f"an empty program in a contained child, median of {LATENCY_RUNS}; {_load()}",
    )


def _seeds_per_minute(case: str, job, **engine) -> Row:
    from openbricks_sim.sweep import sweep

    load_before = _load()
    started = time.perf_counter()
    rows = list(sweep(job, range(1, SEEDS + 1), **engine))
    took = time.perf_counter() - started
    assert len(rows) == SEEDS and all(r.result.exit == "finished" for r in rows)
    return Row(case, SEEDS / took * 60, "seeds/min", f"{SEEDS} seeds in {took:.1f} s; {load_before}")


def _one_warm_run_per_minute(job) -> float:
    """Seeds a minute one at a time, each forked from a fork server that has warmed up."""
    from dataclasses import replace

    from openbricks_sim.fork_server import ForkServer
    from openbricks_sim.run_process import run_in_child

    with ForkServer() as forker:
        run_in_child(job, quiet=True, forker=forker)  # waits for the server's imports
        started = time.perf_counter()
        for seed in range(1, WARM_RUNS + 1):
            result, _ = run_in_child(replace(job, seed=seed), quiet=True, forker=forker)
            assert result.exit == "finished", result.error
        return WARM_RUNS / (time.perf_counter() - started) * 60


@contextlib.contextmanager
def _warm_runs(folder: str, on: bool):
    """Sweeps in this block find the user's shared warm server (sim/shared_server.py) running, in a
    runtime folder of the benchmark's own, or find none; the server is stopped after."""
    from openbricks_sim import shared_server

    saved = {
        name: os.environ.get(name) for name in (shared_server.DISABLE_ENV, shared_server.RUNTIME_DIR_ENV)
    }
    os.environ[shared_server.RUNTIME_DIR_ENV] = os.path.join(folder, "runtime")
    os.environ[shared_server.DISABLE_ENV] = "1" if on else "0"
    path = None
    try:
        if on:
            path = shared_server.socket_path()
            shared_server.start_in_background()
            deadline = time.monotonic() + 120
            while (client := shared_server.connect()) is None:
                if time.monotonic() > deadline:
                    raise RuntimeError("the shared warm server did not start within 120 s")
                time.sleep(0.05)
            client.close()
        yield
    finally:
        pid = shared_server.server_pid(path) if path else None
        if pid is not None:
            os.kill(pid, signal.SIGTERM)
        for name, value in saved.items():
            if value is None:
                os.environ.pop(name, None)
            else:
                os.environ[name] = value


def run() -> list[Row]:
    from distributed import LocalCluster

    from openbricks_sim.job import SimJob
    from tests.sim.test_sweep import CURVE  # the drive the sweep tests run

    rows = []
    with tempfile.TemporaryDirectory(prefix="bench-sweep-") as folder:
        rows.append(_start_latency(folder, "empty"))
        rows.append(_start_latency(folder, "wro"))
        program = os.path.join(folder, "drive.py")
        with open(program, "w") as f:
            f.write(CURVE)
        job = SimJob(program, world="wro", limit_ms=10_000)
        warm_rate = _one_warm_run_per_minute(job)
        rows.append(Row("one warm run at a time", warm_rate, "seeds/min", f"{WARM_RUNS} seeds; {_load()}"))
        with _warm_runs(folder, on=False):
            pool = _seeds_per_minute(f"local pool, {WORKERS} workers", job, workers=WORKERS)
        rows.append(
            Row(pool.case, pool.value, pool.unit, f"its own fork server, started meanwhile; {pool.note}")
        )
        with _warm_runs(folder, on=True):
            warm_pool = _seeds_per_minute(
                f"local pool, {WORKERS} workers, the user's warm server running", job, workers=WORKERS
            )
        rows.append(warm_pool)
        for case, measured in (("", pool), (", warm server", warm_pool)):
            rows.append(
                Row(
                    f"pool{case} / ({WORKERS} x one warm run)",
                    measured.value / (WORKERS * warm_rate),
                    "x",
                    "how busy the sweep keeps the cores; bar: >= 0.9",
                )
            )
        started = time.perf_counter()
        with LocalCluster(
            n_workers=WORKERS, threads_per_worker=1, processes=True, host="127.0.0.1", dashboard_address=None
        ) as cluster:
            rows.append(Row("Dask LocalCluster start", (time.perf_counter() - started) * 1000, "ms", _load()))
            rows.append(
                _seeds_per_minute(
                    f"Dask LocalCluster, {WORKERS} worker processes", job, dask=cluster.scheduler_address
                )
            )
    return rows
