"""`openbricks --help` start-up time, ours next to the reference CLI (openbricks 4.36.0 from PyPI).

The reference is installed once into a throwaway venv under the user cache dir (never imported here:
both CLIs run as subprocesses, the way a user starts them). Each figure is the median wall time of
RUNS cold-ish starts after WARMUP runs that fill the OS file cache, so the ratio compares the CLIs'
own import work rather than disk reads.
"""

from __future__ import annotations

import os
import shutil
import statistics
import subprocess
import sys
import time
import venv
from pathlib import Path

from benchmarks import Row

REFERENCE = "openbricks==4.36.0"
RUNS = 21
WARMUP = 3


def reference_venv() -> Path:
    from openbricks_server.paths import cache_dir

    return cache_dir() / "reference-cli-4.36.0"


def reference_cli() -> Path:
    """The reference `openbricks` script, installing it into its venv on first use."""
    root = reference_venv()
    script = root / "bin" / "openbricks"
    if script.exists():
        return script
    if root.exists():
        shutil.rmtree(root)  # a half-made venv from an interrupted install
    venv.EnvBuilder(with_pip=True).create(root)
    subprocess.run(
        [
            str(root / "bin" / "python"),
            "-m",
            "pip",
            "install",
            "-q",
            "--disable-pip-version-check",
            REFERENCE,
        ],
        check=True,
        timeout=900,
    )
    return script


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
    reference = median_ms([str(reference_cli()), "--help"])
    return [
        Row("openbricks --help (ours)", ours, "ms", f"median of {RUNS}"),
        Row("openbricks --help (reference 4.36.0)", reference, "ms", f"median of {RUNS}"),
        Row("ours / reference", ours / reference, "x", "target <= 1.0"),
    ]
