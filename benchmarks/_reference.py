"""The reference implementation, openbricks 4.36.0 from PyPI, for side-by-side figures.

It is installed once, with its simulator extra, into a throwaway venv under the user cache dir and
only ever run as a subprocess of that venv's interpreter: the project never imports it. (The leading
underscore keeps the benchmark runner from taking this helper for a benchmark.)
"""

from __future__ import annotations

import shutil
import subprocess
import venv
from pathlib import Path

REFERENCE = "openbricks[sim]==4.36.0"


def venv_dir() -> Path:
    from openbricks_server.paths import cache_dir

    return cache_dir() / "reference-4.36.0"


def python() -> Path:
    """The reference venv's interpreter, creating the venv on first use."""
    root = venv_dir()
    interpreter = root / "bin" / "python"
    marker = root / ".installed"
    if marker.exists():
        return interpreter
    if root.exists():
        shutil.rmtree(root)  # a half-made venv from an interrupted install
    venv.EnvBuilder(with_pip=True).create(root)
    subprocess.run(
        [str(interpreter), "-m", "pip", "install", "-q", "--disable-pip-version-check", REFERENCE],
        check=True,
        timeout=1200,
    )
    marker.touch()
    return interpreter


def script(name: str) -> Path:
    """A console script of the reference (e.g. "openbricks"), installing it on first use."""
    return python().with_name(name)


def run_python(code: str, timeout_s: float = 600) -> str:
    """Run `code` in the reference's interpreter and return its stdout."""
    result = subprocess.run(
        [str(python()), "-c", code], capture_output=True, text=True, check=True, timeout=timeout_s
    )
    return result.stdout
