"""The serial-bus engine's cost with two adopted wheels: CPU time per tick, and wire time per tick.

The figures come from ``native/bench_bus_engine.c``, compiled here with ``gcc -O2`` against the cores
in ``firmware/native``: the engine's 1 kHz tick (a sync write of both duties, a feedback read of each
wheel) over an in-memory wire that answers like two ST-3032s and counts 10 us per byte at 1 Mbaud,
20 us before each reply. CPU time is the host's; the wire time is what the same tick occupies on a
hub's bus, shown as a share of the 1 ms tick.
"""

from __future__ import annotations

import shutil
import subprocess
import tempfile
from pathlib import Path

from benchmarks import Row

REPO = Path(__file__).resolve().parent.parent
NATIVE = REPO / "firmware" / "native"
BENCH_SOURCE = Path(__file__).resolve().parent / "native" / "bench_bus_engine.c"
CORES = ("serial_bus", "scs")
TICK_US = 1000


def run() -> list[Row]:
    compiler = shutil.which("gcc") or shutil.which("cc")
    if compiler is None:
        raise RuntimeError("no C compiler on PATH (gcc or cc): needed for the bus engine benchmark")
    with tempfile.TemporaryDirectory(prefix="ob-bench-") as tmp:
        exe = Path(tmp) / "bench_bus_engine"
        sources = [str(BENCH_SOURCE)] + [str(NATIVE / f"{core}.c") for core in CORES]
        subprocess.run(
            [compiler, "-std=c99", "-O2", f"-I{NATIVE}", *sources, "-lm", "-o", str(exe)],
            check=True,
            capture_output=True,
            text=True,
        )
        out = subprocess.run([str(exe)], check=True, capture_output=True, text=True).stdout
    figures = {line.split()[0]: [float(v) for v in line.split()[1:]] for line in out.splitlines()}
    best_ns, median_ns = figures["engine_tick"]
    last_us, mean_us = figures["bus_us"]
    return [
        Row(
            "engine CPU per tick, 2 wheels (host, C)",
            best_ns / 1000,
            "us",
            f"best of 7; median {median_ns / 1000:.2f} us",
        ),
        Row("bus time per tick at 1 Mbaud", mean_us, "us", "sync write of 2 duties + 2 feedback reads"),
        Row("bus share of the 1 ms tick", 100 * mean_us / TICK_US, "%", f"last tick {last_us:.0f} us"),
    ]
