"""examples/host/run_on_every_hub.py, the console guide's REST script, against a real console with two
virtual hubs (simulator behind each), run the way its docstring says."""

import re
import subprocess
import sys
from pathlib import Path

import pytest

from tests.web.console_process import start_console, stop_console

pytestmark = pytest.mark.e2e
EXAMPLES = Path(__file__).resolve().parents[2] / "examples"


def test_the_script_runs_the_program_on_both_hubs_and_tabulates_their_outcomes(tmp_path):
    console = start_console(tmp_path)
    try:
        hubs = console.wait_hubs_idle(2)
        done = subprocess.run(
            [sys.executable, str(EXAMPLES / "host" / "run_on_every_hub.py"), str(EXAMPLES / "first_robot.py")]
            + ["--console", console.base, "--token", console.token],
            capture_output=True,
            text=True,
            timeout=300,
        )
    finally:
        stop_console(console.process)
    assert done.returncode == 0, done.stderr
    rows = re.findall(r"^(\S+)\s+finished\s+(\d+) lines  last: home again after 1000 mm$", done.stdout, re.M)
    assert sorted(name for name, _ in rows) == sorted(h["name"] for h in hubs), done.stdout
