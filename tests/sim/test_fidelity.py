"""The product's fidelity bars, measured on the simulated robot through the unchanged runtime:
ST3032Motor wheels adopted by openbricks.robotics.DriveBase onto the emulated bus engine.

Each figure is the robot's true pose from the physics, not the controller's own odometry."""

import math

import pytest

from openbricks_sim.shim import Shim
from openbricks_sim.simulation import Simulation


@pytest.fixture
def robot():
    sim = Simulation("empty", "st3032", epoch_ms=0)
    with Shim(sim):
        from openbricks.drivers.st3032 import ST3032Motor
        from openbricks.robotics import DriveBase

        db = DriveBase(ST3032Motor(1), ST3032Motor(2, invert=True), wheel_diameter_mm=88, axle_track_mm=138)
        yield sim, db
        db.close()
    sim.close()


def test_straight_1000_ends_within_2_mm(robot):
    sim, db = robot
    start = sim.physics.pose()
    db.straight(1000)
    end = sim.physics.pose()
    travelled = math.hypot(end.x_mm - start.x_mm, end.y_mm - start.y_mm)
    assert travelled == pytest.approx(1000, abs=2.0)


def test_turn_90_ends_within_half_a_degree(robot):
    sim, db = robot
    db.turn(90)
    assert sim.physics.pose().heading_deg == pytest.approx(90.0, abs=0.5)


def test_a_300_mm_square_closes_within_10_mm_and_2_degrees(robot):
    sim, db = robot
    start = sim.physics.pose()
    for _ in range(4):
        db.straight(300)
        db.turn(90)
    end = sim.physics.pose()
    gap = math.hypot(end.x_mm - start.x_mm, end.y_mm - start.y_mm)
    heading_error = (end.heading_deg - start.heading_deg + 180) % 360 - 180
    assert gap < 10.0, f"the square opened by {gap:.1f} mm"
    assert abs(heading_error) < 2.0


def test_curve_traces_a_circle_within_2_mm_radial_error(robot):
    import time

    sim, db = robot
    radius = 250.0
    start = sim.physics.pose()
    # Turning right (clockwise) around a centre on the robot's right-hand side.
    heading = math.radians(start.heading_deg)
    centre = (start.x_mm - radius * math.sin(heading), start.y_mm - radius * math.cos(heading))
    db.curve(radius, 360, wait=False)
    worst = 0.0
    while not db.done():
        time.sleep_ms(20)
        pose = sim.physics.pose()
        worst = max(worst, abs(math.hypot(pose.x_mm - centre[0], pose.y_mm - centre[1]) - radius))
    assert worst < 2.0, f"{worst:.2f} mm off the circle"


def test_a_wheel_with_a_tenth_less_torque_keeps_the_heading_error_under_5_percent_of_distance(robot):
    sim, db = robot
    sim.controller.set_torque_scale(1, 0.9)  # the right motor is weaker
    start = sim.physics.pose()
    db.straight(1000)
    end = sim.physics.pose()
    lateral = abs(end.y_mm - start.y_mm)
    assert lateral < 0.05 * 1000
    assert abs(end.heading_deg - start.heading_deg) < 1.0
