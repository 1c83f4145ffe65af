"""list shows the virtual hubs (marked); paste-probe measures the raw-paste path of one."""

import json
import re

import pytest

from .conftest import cli

pytestmark = pytest.mark.e2e


def test_list_marks_virtual_hubs_and_survives_a_missing_bluetooth_adapter(env, hub):
    done = cli(env, "list", "--timeout", "0.5")
    assert done.returncode == 0, done.stderr
    assert re.search(rf"^RobotA\s+virtual\s+{re.escape(hub.pty)}\s+idle$", done.stdout, re.MULTILINE)


def test_list_json_gives_scripts_the_same_hubs_with_stable_keys(env, hub):
    done = cli(env, "list", "--timeout", "0.5", "--json")
    assert done.returncode == 0, done.stderr
    hubs = json.loads(done.stdout)
    assert {"name": "RobotA", "kind": "virtual", "address": hub.pty, "status": "idle"} in hubs


def test_paste_probe_reports_each_size_and_the_window(env, hub):
    window = hub.control("status")["paste_window"]
    done = cli(env, "paste-probe", "-n", "RobotA", "--max", "3000", "--timeout", "20")
    assert done.returncode == 0, done.stderr
    sizes = [int(n) for n in re.findall(r"^\s*(\d+) bytes\s+ok", done.stdout, re.MULTILINE)]
    assert sizes == [256, 512, 1024, 2048, 3000]
    assert f"raw-paste window granted by RobotA: {window} bytes" in done.stdout
    assert "largest program that completed: 3000 bytes" in done.stdout
