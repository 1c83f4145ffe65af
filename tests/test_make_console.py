"""`make console`, the first command a new user types, from a fresh clone: what it would install and run.

A real fresh run takes about two minutes (a new venv, npm ci, the manual's Sphinx build), too long for
every test run, so the clone's `make -n console` is read instead: it must install only the console's
and the manual's extras (no dev extra with pytest and Playwright, no apt packages such as Chromium or
the cross compilers, no runtime-test npm package, no MicroPython build needing ../shared), build the pages
and the manual the Manual link opens, and hand ARGS to `openbricks console`. That /manual/ is then served
by a running console is tests/web/test_manual_link.py's; the option names are checked against the
parser itself.
"""

from __future__ import annotations

import os
import re
import shlex
import shutil
import subprocess
from pathlib import Path

import pytest

from openbricks_server.cli import build_parser

ROOT = Path(__file__).resolve().parent.parent
ARGS = "--port 9000 --no-ble"
SETUP_FILES = ("Makefile", "pyproject.toml", "setup.py", "build_backend.py")

pytestmark = pytest.mark.e2e


@pytest.fixture(scope="module")
def plan(tmp_path_factory) -> list[str]:
    clone = tmp_path_factory.mktemp("fresh") / "openbricks"
    subprocess.run(["git", "clone", "-q", "--no-hardlinks", str(ROOT), str(clone)], check=True, timeout=120)
    for name in SETUP_FILES:  # as the working tree has them, so an edit is tested before it is committed
        shutil.copyfile(ROOT / name, clone / name)
    # A make of its own, as a user's shell starts it: not a sub-make of the `make test` running us,
    # whose flags would add "Entering directory" lines.
    env = {
        k: v for k, v in os.environ.items() if k not in ("MAKEFLAGS", "MAKELEVEL", "MFLAGS", "MAKEOVERRIDES")
    }
    done = subprocess.run(
        ["make", "-n", "console", f"ARGS={ARGS}"],
        cwd=clone,
        capture_output=True,
        text=True,
        timeout=60,
        env=env,
    )
    assert done.returncode == 0, done.stderr
    return done.stdout.splitlines()


def test_it_installs_the_console_and_the_manual_and_no_test_tooling(plan):
    installs = [line for line in plan if re.search(r"pip install .*-e ", line)]
    assert installs == [".venv/bin/python -m pip install -q -e '.[sim,docs]'"], installs
    text = "\n".join(plan)
    absents = ("dev]", "dev,", "apt-get", "chromium", "gcc-multilib", "xtensa", "tests/micropython")
    for absent in (*absents, "playwright"):
        assert absent not in text, f"`make console` must not need {absent!r}:\n{text}"
    assert "unix_micropython.py" not in text, "the console needs no MicroPython build (nor ../shared)"


def test_it_builds_the_pages_and_the_manual_then_passes_the_options_on(plan):
    text = "\n".join(plan)
    assert "npm run build" in text
    assert re.search(r"sphinx .* docs server/docs_html", text), "the manual the Manual link (/manual/) opens"
    last = plan[-1]
    assert last == f".venv/bin/openbricks console {ARGS}", last
    # The options are real `openbricks console` options.
    args = build_parser().parse_args(["console", *shlex.split(ARGS)])
    assert args.port == 9000 and args.no_ble
