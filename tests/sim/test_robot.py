"""How each chassis is wired to the simulated hub: the DC build's bridge and encoders."""

import pytest

from openbricks_sim.shim import Shim
from openbricks_sim.simulation import Simulation


@pytest.fixture
def dc_robot():
    s = Simulation("empty", "jgb37", epoch_ms=0)
    with Shim(s):
        yield s
    s.close()


def test_the_l298n_bridge_drives_the_wheels_and_pcnt_counts_their_encoders(dc_robot):
    import time

    from openbricks.drivers.encoder import PCNTEncoder
    from openbricks.drivers.l298n import L298NMotor

    left = L298NMotor(1, 2, 17)
    right = L298NMotor(9, 10, 11, invert=True)  # mounted mirror-image, as on the real build
    encoder = PCNTEncoder(7, 8, unit=0)
    left.dc(60)
    right.dc(60)
    time.sleep_ms(1000)
    pose = dc_robot.physics.pose()
    assert pose.x_mm > 200 and abs(pose.heading_deg) < 2
    wheel_deg = dc_robot.physics.wheel_angle_deg(0)
    assert encoder.count() == pytest.approx(wheel_deg * 1320 / 360, abs=2)
    left.brake()
    right.coast()
    time.sleep_ms(500)
    assert abs(dc_robot.physics.wheel_io(0).speed_dps) < 5, "a shorted winding stops the wheel"


def test_the_dc_robot_has_no_serial_bus(dc_robot):
    import _openbricks_native

    with pytest.raises(OSError, match="no serial-bus servos"):
        _openbricks_native.serial_bus(1)
