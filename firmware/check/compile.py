"""Compile the firmware's C files for Xtensa, one object each, and gather the compiler's verdicts."""

import os
import re
import subprocess
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass, field
from pathlib import Path

from flags import MODULE_DIR, NATIVE

COMPILE_LIMIT_S = 300
WARNING = re.compile(r":\d+:\d+: warning:")
ERROR = re.compile(r":\d+:\d+: (?:fatal )?error:")


@dataclass
class Outcome:
    compiled: list = field(default_factory=list)  # objects written
    warnings: int = 0
    failed: list = field(default_factory=list)  # sources that did not compile
    messages: list = field(default_factory=list)  # the compiler's output, per source


def firmware_sources():
    """Every C file of the image that is ours: the cores and the MicroPython module, glue included.

    platform/ holds the host's timer (a POSIX thread), which the image replaces with esp_timer.
    """
    return sorted(NATIVE.glob("*.c")) + sorted(MODULE_DIR.glob("*.c"))


def _object_path(source, objects):
    source = Path(source).resolve()
    try:
        relative = source.relative_to(NATIVE)
    except ValueError:
        relative = Path("elsewhere") / source.name
    return objects / relative.with_suffix(".o")


def _compile_one(compiler, cpp_flags, c_flags, source, objects):
    obj = _object_path(source, objects)
    obj.parent.mkdir(parents=True, exist_ok=True)
    command = [*compiler, *c_flags, *cpp_flags, "-c", str(source), "-o", str(obj)]
    try:
        result = subprocess.run(command, capture_output=True, text=True, timeout=COMPILE_LIMIT_S)
        output, ok = result.stdout + result.stderr, result.returncode == 0
    except subprocess.TimeoutExpired:
        output, ok = f"{source}: the compiler did not finish within {COMPILE_LIMIT_S} s\n", False
    return source, obj, ok, output


def compile_all(compiler, cpp_flags, c_flags, sources, objects, jobs=None):
    outcome = Outcome()
    jobs = jobs or os.cpu_count() or 2
    with ThreadPoolExecutor(max_workers=jobs) as pool:
        results = pool.map(lambda s: _compile_one(compiler, cpp_flags, c_flags, s, objects), sources)
        for source, obj, ok, output in results:
            outcome.warnings += len(WARNING.findall(output))
            if output.strip():
                outcome.messages.append(output.rstrip())
            if ok:
                outcome.compiled.append(obj)
            else:
                outcome.failed.append(source)
    return outcome
