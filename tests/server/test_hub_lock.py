"""Two commands never talk to one hub at once."""

import subprocess
import sys

import pytest

from openbricks_server.hub_lock import HubBusyError, hub_lock, lock_path


@pytest.fixture(autouse=True)
def data_dir(tmp_path, monkeypatch):
    monkeypatch.setenv("OPENBRICKS_DATA_DIR", str(tmp_path))
    return tmp_path


def test_a_second_process_finds_the_hub_busy_and_gets_it_after_release(data_dir):
    probe = (
        "from openbricks_server.hub_lock import hub_lock, HubBusyError\n"
        "try:\n"
        "    with hub_lock('RobotA'):\n"
        "        print('got it')\n"
        "except HubBusyError as e:\n"
        "    print(e)\n"
    )
    with hub_lock("RobotA"):
        busy = subprocess.run([sys.executable, "-c", probe], capture_output=True, text=True, timeout=30)
        assert "hub 'RobotA' is busy" in busy.stdout
        with pytest.raises(HubBusyError):
            with hub_lock("RobotA"):
                pass
    free = subprocess.run([sys.executable, "-c", probe], capture_output=True, text=True, timeout=30)
    assert free.stdout.strip() == "got it"


def test_other_hubs_are_independent():
    with hub_lock("RobotA"):
        with hub_lock("RobotB"):
            pass


def test_lock_files_live_under_the_data_dir_and_keep_odd_names_apart(data_dir):
    assert lock_path("Robot/A").parent == data_dir / "locks"
    assert lock_path("Robot/A") != lock_path("Robot_A")
