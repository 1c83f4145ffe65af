"""The serial-bus engine's cost with two adopted wheels: CPU time per tick, and wire time per tick.

The figures come from ``native/bench_bus_engine.c``, compiled here with ``gcc -O2`` against the cores
in ``firmware/native``: the engine's 1 kHz tick (a sync write of both duties, a feedback read of each
wheel) over an in-memory wire that answers like two ST-3032s and counts 10 us per byte at 1 Mbaud,
20 us before each reply. CPU time is the host's; the wire time is what the same tick occupies on a
hub's bus, shown as a share of the 1 ms tick.
"""

from __future__ import annotations

from benchmarks import Row
from benchmarks._native_bench import run_c_benchmark

CORES = ("serial_bus", "scs", "servo", "control", "trajectory", "observer")  # servo: the slots' st_move_core
TICK_US = 1000


def run() -> list[Row]:
    out = run_c_benchmark("bench_bus_engine.c", CORES)
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
