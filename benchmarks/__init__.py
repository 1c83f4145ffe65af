"""Performance figures of openbricks: `python -m benchmarks` (or `make bench`) runs every module here.

A benchmark module is any module in this package whose name does not start with an underscore and
that defines ``run() -> list[Row]``. Benchmarks measure and print; they never assert a time, because
the figures depend on the machine and are read by people, not gated on.
"""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class Row:
    """One measured figure: what was measured, the number, its unit, and how to read it."""

    case: str
    value: float
    unit: str
    note: str = ""
