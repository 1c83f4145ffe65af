"""How long the documentation site takes to build (`make docs`): from scratch, and again after one page
changed, as a writer edits. Wall time and the build's own CPU time (the CPU figure is what a busy
machine does not distort), the page count and the site's size.

The site is built into a temporary folder with the Makefile's flags (warnings are errors), so the
package's copy (server/docs_html) is left alone.
"""

from __future__ import annotations

import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from benchmarks import Row

ROOT = Path(__file__).resolve().parent.parent
DOCS = ROOT / "docs"
EDITED_PAGE = DOCS / "troubleshooting.md"


def build(out: Path, doctrees: Path) -> tuple[float, float]:
    """(wall s, CPU s) of one sphinx-build run."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    started = time.perf_counter()
    subprocess.run(
        [sys.executable, "-m", "sphinx", "-W", "--keep-going", "-q", "-b", "html", "-d", str(doctrees)]
        + [str(DOCS), str(out)],
        check=True,
        capture_output=True,
    )
    wall = time.perf_counter() - started
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    return wall, (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)


def run() -> list[Row]:
    with tempfile.TemporaryDirectory() as tmp:
        out, doctrees = Path(tmp) / "html", Path(tmp) / "doctrees"
        clean_wall, clean_cpu = build(out, doctrees)
        EDITED_PAGE.touch()
        again_wall, again_cpu = build(out, doctrees)
        pages = [p for p in out.rglob("*.html") if p.stem not in ("genindex", "search", "py-modindex")]
        size_mb = sum(p.stat().st_size for p in out.rglob("*") if p.is_file()) / 1e6
    return [
        Row("from scratch: wall", clean_wall, "s"),
        Row("from scratch: CPU", clean_cpu, "s", "sphinx-build's own user + system time"),
        Row("one page edited: wall", again_wall, "s", f"after touching {EDITED_PAGE.name}"),
        Row("one page edited: CPU", again_cpu, "s"),
        Row("pages", len(pages), "pages", "without the index and search pages Sphinx adds"),
        Row("site size", size_mb, "MB", "what the wheel carries"),
    ]
