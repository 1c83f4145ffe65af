"""`openbricks --help` start-up time, ours next to the reference CLI (openbricks 4.36.0 from PyPI).

The reference lives in the benchmarks' throwaway venv (benchmarks._reference; never imported here:
both CLIs run as subprocesses, the way a user starts them). Each figure is the median wall time of
RUNS cold-ish starts after WARMUP runs that fill the OS file cache, so the ratio compares the CLIs'
own import work rather than disk reads.
"""

from __future__ import annotations

import os
import statistics
import subprocess
import sys
import time
from pathlib import Path

from benchmarks import Row, _reference

RUNS = 21
WARMUP = 3


def ours_cli() -> Path:
    script = Path(sys.executable).with_name("openbricks")
    if not script.exists():
        raise RuntimeError(f"no console script at {script}: install the project (make setup)")
    return script


def median_ms(argv: list[str]) -> float:
    env = dict(os.environ, PYTHONDONTWRITEBYTECODE="1")
    for _ in range(WARMUP):
        subprocess.run(argv, capture_output=True, check=True, env=env)
    times = []
    for _ in range(RUNS):
        started = time.perf_counter()
        subprocess.run(argv, capture_output=True, check=True, env=env)
        times.append((time.perf_counter() - started) * 1000)
    return statistics.median(times)


def run() -> list[Row]:
    ours = median_ms([str(ours_cli()), "--help"])
    reference = median_ms([str(_reference.script("openbricks")), "--help"])
    return [
        Row("openbricks --help (ours)", ours, "ms", f"median of {RUNS}"),
        Row("openbricks --help (reference 4.36.0)", reference, "ms", f"median of {RUNS}"),
        Row("ours / reference", ours / reference, "x", "target <= 1.0"),
    ]
