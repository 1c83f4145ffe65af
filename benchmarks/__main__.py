"""Run the benchmark modules of this package and print their figures as one table.

python -m benchmarks                 # every module
python -m benchmarks control_ticks   # only the named ones
"""

from __future__ import annotations

import importlib
import pkgutil
import sys
import time
import traceback
from pathlib import Path

from benchmarks import Row


def discover() -> list[str]:
    """Benchmark module names, in alphabetical order: new modules are picked up without registration."""
    here = Path(__file__).parent
    return sorted(
        info.name
        for info in pkgutil.iter_modules([str(here)])
        if not info.ispkg and not info.name.startswith("_")
    )


def format_value(value: float) -> str:
    return f"{value:,.1f}" if abs(value) < 1e6 else f"{value:,.0f}"


def print_table(section: str, rows: list[Row], seconds: float) -> None:
    print(f"\n{section}  ({seconds:.1f} s)")
    if not rows:
        print("  (no figures)")
        return
    case_width = max(len(r.case) for r in rows)
    value_width = max(len(format_value(r.value)) for r in rows)
    unit_width = max(len(r.unit) for r in rows)
    for r in rows:
        line = f"  {r.case:<{case_width}}  {format_value(r.value):>{value_width}} {r.unit:<{unit_width}}"
        print(f"{line}  {r.note}".rstrip())


def main(argv: list[str]) -> int:
    available = discover()
    wanted = argv or available
    unknown = sorted(set(wanted) - set(available))
    if unknown:
        print(
            f"unknown benchmark(s): {', '.join(unknown)}; available: {', '.join(available)}", file=sys.stderr
        )
        return 2
    failed = []
    for name in wanted:
        start = time.perf_counter()
        try:
            module = importlib.import_module(f"benchmarks.{name}")
            rows = module.run()
        except Exception:  # one broken benchmark must not hide the others' figures
            failed.append(name)
            print(f"\n{name}: FAILED", file=sys.stderr)
            traceback.print_exc()
            continue
        print_table(name, rows, time.perf_counter() - start)
    if failed:
        print(f"\nbenchmarks that failed to run: {', '.join(failed)}", file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
