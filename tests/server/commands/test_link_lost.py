"""A hub that vanishes mid-run: reported at once, with the output already received kept."""

import subprocess
import sys
import time

import pytest

from .conftest import HubProcess

pytestmark = pytest.mark.e2e


def test_a_lost_link_is_reported_within_two_seconds_with_the_output_kept(tmp_path):
    hub = HubProcess("Vanishing", tmp_path / "data")
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
        while "line 5" not in received:
            received += cli.stdout.readline()
        hub.process.kill()
        killed = time.monotonic()
        out, err = cli.communicate(timeout=30)
        reported_after_s = time.monotonic() - killed
    finally:
        cli.kill()
        hub.stop()
    assert cli.returncode == 1
    assert reported_after_s < 2.0
    assert "line 5" in received + out
    assert "the link to Vanishing was lost" in err and "what arrived before is shown above" in err
    assert "Traceback" not in err
