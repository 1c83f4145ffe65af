"""servo-id through a hub: the virtual hub's simulated bus carries the robot's two ST-3032 servos."""

import pytest

from .conftest import HubProcess, cli, console_holding

pytestmark = pytest.mark.e2e


def test_scan_and_re_id_through_the_hub(env):
    scan = cli(env, "servo-id", "-n", "RobotA", "--scan")
    assert scan.returncode == 0, scan.stderr
    assert scan.stdout.strip() == "servo ids on RobotA's servo bus: 1, 2"
    guess = cli(env, "servo-id", "-n", "RobotA", "7")
    assert guess.returncode == 1 and "pass --old-id to say which one" in guess.stderr
    taken = cli(env, "servo-id", "-n", "RobotA", "1", "--old-id", "2")
    assert taken.returncode == 1 and "id 1 is already taken" in taken.stderr
    done = cli(env, "servo-id", "-n", "RobotA", "7", "--old-id", "2")
    assert done.returncode == 0, done.stderr
    assert "servo 2 is now id 7 (read back from the servo); ids on the bus: 1, 7" in done.stdout
    assert cli(env, "servo-id", "-n", "RobotA", "--scan").stdout.strip().endswith("1, 7")


def test_bad_ids_are_refused_before_connecting(env):
    done = cli(env, "servo-id", "-n", "RobotA", "300")
    assert done.returncode == 2 and "servo bus ids are 0..253" in done.stderr
    assert cli(env, "servo-id", "-n", "RobotA").returncode == 2  # neither NEW_ID nor --scan


def test_a_port_the_console_holds_is_refused_with_how_to_reach_its_servos(tmp_path):
    """-p names a servo bus adapter; a port the console holds is a hub's link, and writing servo
    packets into it would garble the console's session with the hub."""
    hub = HubProcess("HeldHub", tmp_path / "data")
    try:
        with console_holding(hub.env, hub.pty, tmp_path) as (url, env):
            done = cli(env, "servo-id", "-p", hub.pty, "--scan")
        assert done.returncode == 1
        assert f"the console ({url}) holds hub pts-" in done.stderr
        assert "from the console (its Servo-ID page" in done.stderr and "Traceback" not in done.stderr
    finally:
        hub.stop()
