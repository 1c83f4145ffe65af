"""A hub that vanishes mid-run: reported at once, with the output already received kept."""

import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import pytest

from .conftest import HubProcess

pytestmark = pytest.mark.e2e


def test_a_lost_link_is_reported_within_two_seconds_with_the_output_kept(tmp_path):
    # A short data dir: discovery finds a hub by the control socket in its folder, whose path must fit
    # a Unix socket address (this test's own tmp_path is too deep for that).
    hub = HubProcess("Vanishing", Path(tempfile.mkdtemp(prefix="ob-e2e-")))
    program = tmp_path / "forever.py"
    program.write_text(
        "import time\nn = 0\nwhile True:\n    print('line', n)\n    n += 1\n    time.sleep_ms(50)\n"
    )
    cli = subprocess.Popen(
        [sys.executable, "-m", "openbricks_server.cli", "run", "-n", "Vanishing", str(program)],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        env=hub.env,
    )
    try:
        received = ""
        deadline = time.monotonic() + 60
        while "line 5" not in received:
            line = cli.stdout.readline()
            if not line or time.monotonic() > deadline:
                raise AssertionError(f"the run ended before line 5: {received!r} {cli.stderr.read()}")
            received += line
        hub.process.kill()
        killed = time.monotonic()
        out, err = cli.communicate(timeout=30)
        reported_after_s = time.monotonic() - killed
    finally:
        cli.kill()
        hub.stop()
        shutil.rmtree(hub.data_dir, ignore_errors=True)
    assert cli.returncode == 1
    assert reported_after_s < 2.0
    assert "line 5" in received + out
    assert "the link to Vanishing was lost" in err and "what arrived before is shown above" in err
    assert "Traceback" not in err
