"""What the hard tick's sensor reads cost each millisecond: a PCNT encoder poll and an ICM-45686 burst.

The CPU figures come from ``native/bench_sensors.c``, compiled here with ``gcc -O2`` against the cores
in ``firmware/native``: the encoder core reading a counter (unwrap and accumulate) and the ICM-45686
core taking one burst from an in-memory chip (parse, scale, integrate the heading). They are the
host's; the peripheral's own time is not in them. The SPI wire time of one burst (13 bytes at the
driver's 8 MHz) is computed, as a share of the 1 ms tick.
"""

from __future__ import annotations

from benchmarks import Row
from benchmarks._native_bench import run_c_benchmark

CORES = ("encoder", "icm45686", "imu_yaw")
TICK_US = 1000
BURST_BYTES = 13
SPI_HZ = 8_000_000


def run() -> list[Row]:
    out = run_c_benchmark("bench_sensors.c", CORES)
    figures = {line.split()[0]: [float(v) for v in line.split()[1:]] for line in out.splitlines()}
    rows = []
    for key, case in (
        ("encoder_poll", "PCNT encoder poll (host, C)"),
        ("icm45686_sample", "ICM-45686 burst + heading (host, C)"),
    ):
        best_ns, median_ns = figures[key]
        rows.append(Row(case, best_ns, "ns", f"best of 7; median {median_ns:.1f} ns"))
    wire_us = BURST_BYTES * 8 / SPI_HZ * 1e6
    rows.append(
        Row("ICM-45686 burst on the wire at 8 MHz", wire_us, "us", "13 bytes, one chip-select window")
    )
    rows.append(Row("burst share of the 1 ms tick", 100 * wire_us / TICK_US, "%", "the manual's ~13 us"))
    return rows
