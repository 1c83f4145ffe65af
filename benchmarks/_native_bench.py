"""Build a pure-C benchmark program against the control cores and run it: the figures of the cores
with no binding in the way. Both the tick and the bus-engine benchmarks are such programs."""

from __future__ import annotations

import shutil
import subprocess
import tempfile
from pathlib import Path

NATIVE = Path(__file__).resolve().parent.parent / "firmware" / "native"
BENCH_DIR = Path(__file__).resolve().parent / "native"


def run_c_benchmark(source_name: str, cores: tuple[str, ...]) -> str:
    """Compile `benchmarks/native/<source_name>` with the named cores at -O2 and return its stdout."""
    compiler = shutil.which("gcc") or shutil.which("cc")
    if compiler is None:
        raise RuntimeError(f"no C compiler on PATH (gcc or cc): needed to build {source_name}")
    with tempfile.TemporaryDirectory(prefix="ob-bench-") as tmp:
        exe = Path(tmp) / Path(source_name).stem
        sources = [str(BENCH_DIR / source_name)] + [str(NATIVE / f"{core}.c") for core in cores]
        subprocess.run(
            [compiler, "-std=c99", "-O2", f"-I{NATIVE}", *sources, "-lm", "-o", str(exe)],
            check=True,
            capture_output=True,
            text=True,
        )
        return subprocess.run([str(exe)], check=True, capture_output=True, text=True).stdout
