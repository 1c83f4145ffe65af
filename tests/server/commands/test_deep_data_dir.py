"""A virtual hub under a data dir too deep for a Unix socket path is still found and driven by name."""

import json
import re

import pytest

from .conftest import HubProcess, cli

pytestmark = pytest.mark.e2e


def test_a_hub_in_a_deep_data_dir_is_listed_and_runs_a_program(tmp_path):
    deep = tmp_path / ("nested-" * 8) / ("folder-" * 8)
    hub = HubProcess("DeepBot", deep)
    try:
        socket_there = hub.directory / "control.sock"
        assert len(str(socket_there)) > 108 and not socket_there.exists()  # the socket had to go elsewhere
        record = json.loads((hub.directory / "endpoint.json").read_text())
        assert record["pty"] == hub.pty and record["control"] == str(hub.control_socket)
        listed = cli(hub.env, "list", "--timeout", "0.5")
        assert listed.returncode == 0, listed.stderr
        assert re.search(rf"^DeepBot\s+virtual\s+{re.escape(hub.pty)}\s+idle$", listed.stdout, re.MULTILINE)
        program = tmp_path / "hello.py"
        program.write_text("print('hello from deep down')\n")
        done = cli(hub.env, "run", "-n", "DeepBot", str(program))
        assert done.returncode == 0, done.stderr
        assert "hello from deep down" in done.stdout
    finally:
        hub.stop()
    assert not (hub.directory / "endpoint.json").exists()  # a stopped hub withdraws its record
