"""examples/host/flash_many.py, the console guide's flashing script, against a real daemon: three boards
(virtual hubs whose ptys stand in for USB ports, as in test_flash.py) flashed with an uploaded image by
the fake esptool, and a port with nothing behind it failing alone in its own row."""

import os
import re
import subprocess
import sys
from pathlib import Path

import pytest

from tests.server.commands.conftest import HubProcess
from tests.server.daemon.conftest import start_daemon
from tests.server.flash.images import build_image

pytestmark = pytest.mark.e2e
EXAMPLES = Path(__file__).resolve().parents[4] / "examples"


def test_the_script_flashes_every_port_it_is_given_and_names_the_hubs_in_order(tmp_path, fake_esptool):
    (tmp_path / "boards").mkdir()
    boards = [HubProcess(f"Board{i}", tmp_path / "boards") for i in (1, 2, 3)]
    daemon = start_daemon(tmp_path / "data")
    try:
        image = tmp_path / "openbricks-esp32s3-firmware-2.8.0.bin"
        image.write_bytes(build_image("esp32s3", version="2.8.0"))
        ports = [board.pty for board in boards] + [boards[0].pty + "-unplugged"]
        done = subprocess.run(
            [sys.executable, str(EXAMPLES / "host" / "flash_many.py"), str(image), "--ports", *ports]
            + ["--console", daemon.url, "--token", daemon.token, "--prefix", "Team"],
            capture_output=True,
            text=True,
            timeout=600,
            env=dict(os.environ),
        )
    finally:
        daemon.stop()
        for board in boards:
            board.stop()
    assert done.returncode == 1, done.stderr  # one port failed
    out = done.stdout
    assert "image openbricks-esp32s3-firmware-2.8.0.bin: esp32s3 2.8.0 at 0x0" in out
    for i, board in enumerate(boards, 1):
        assert re.search(rf"^{re.escape(board.pty)}\s+Team0{i}\s+flashed$", out, re.M), out
        assert board.nvs_blob("openbricks", "hub_name") == f"Team0{i}".encode()
    assert re.search(r"-unplugged\s+Team04\s+failed: .*there is no such port", out), out
    assert "3 of 4 flashed" in out
