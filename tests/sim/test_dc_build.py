"""The DC gear-motor build (chassis jgb37) through the unchanged runtime: two JGB37Motor on the
manual's GPIO map (2.7), their encoders counted by the simulated PCNT units, driven by
openbricks.robotics.DriveBase, with the sensor rig's IMU on pins that build leaves free.

Every figure is the robot's true pose from the physics, not the controller's own odometry."""

import math

import pytest

from openbricks_sim.robot import JGB37_CHANNELS
from openbricks_sim.sensors import rig
from openbricks_sim.shim import Shim
from openbricks_sim.simulation import Simulation

WHEEL_DIAMETER_MM = 65
AXLE_TRACK_MM = 120


def build_motors():
    from openbricks.drivers.jgb37_520 import JGB37Motor

    left = JGB37Motor(in1=1, in2=2, pwm=17, encoder_a=7, encoder_b=8)
    right = JGB37Motor(in1=9, in2=10, pwm=11, encoder_a=12, encoder_b=13, invert=True)
    return left, right


@pytest.fixture
def sim():
    simulation = Simulation("empty", "jgb37", epoch_ms=0)
    with Shim(simulation):
        yield simulation
    simulation.close()


@pytest.fixture
def robot(sim):
    from openbricks.robotics import DriveBase

    left, right = build_motors()
    db = DriveBase(left, right, wheel_diameter_mm=WHEEL_DIAMETER_MM, axle_track_mm=AXLE_TRACK_MM)
    yield sim, db, left, right
    db.close()


def test_straight_1000_ends_within_2_mm(robot):
    sim, db, _, _ = robot
    start = sim.physics.pose()
    db.straight(1000)
    end = sim.physics.pose()
    assert math.hypot(end.x_mm - start.x_mm, end.y_mm - start.y_mm) == pytest.approx(1000, abs=2.0)
    assert abs(end.heading_deg - start.heading_deg) < 0.5


def test_turn_90_ends_within_half_a_degree(robot):
    sim, db, _, _ = robot
    db.turn(90)
    assert sim.physics.pose().heading_deg == pytest.approx(90.0, abs=0.5)


def test_a_300_mm_square_closes_within_10_mm_and_2_degrees(robot):
    sim, db, _, _ = robot
    start = sim.physics.pose()
    for _ in range(4):
        db.straight(300)
        db.turn(90)
    end = sim.physics.pose()
    assert math.hypot(end.x_mm - start.x_mm, end.y_mm - start.y_mm) < 10.0
    assert abs((end.heading_deg - start.heading_deg + 180) % 360 - 180) < 2.0


def test_each_motor_angle_follows_its_wheel_to_an_encoder_count(robot):
    sim, db, left, right = robot
    db.straight(200)
    wheel_deg = 200 / (math.pi * WHEEL_DIAMETER_MM) * 360
    count_deg = 360 / 1320
    for motor, wheel in ((left, 0), (right, 1)):
        # Both wheel joints turn forward-positive; the mirrored right motor's user frame is too.
        assert motor.angle() == pytest.approx(sim.physics.wheel_angle_deg(wheel), abs=2 * count_deg)
        assert motor.angle() == pytest.approx(wheel_deg, abs=3.0)


def test_a_single_motor_runs_its_closed_loop_on_the_wheel(sim):
    left, _ = build_motors()
    left.run_angle(360, 720, then="hold")
    assert sim.physics.wheel_angle_deg(0) == pytest.approx(720, abs=2.0)
    left.run_speed(300)
    import time

    time.sleep_ms(1000)
    assert left.speed() == pytest.approx(300, abs=15)
    left.brake()


def test_the_imu_and_the_motors_work_together_on_the_dc_build(sim):
    import time

    from openbricks.drivers.icm45686 import ICM45686
    from openbricks.robotics import DriveBase

    pins = rig.icm45686_spi("jgb37")
    imu = ICM45686(sck=pins.sck, mosi=pins.mosi, miso=pins.miso, cs=pins.cs)
    while not imu.calibrated():
        time.sleep_ms(50)
    imu.reset_heading(0)
    left, right = build_motors()
    db = DriveBase(left, right, wheel_diameter_mm=WHEEL_DIAMETER_MM, axle_track_mm=AXLE_TRACK_MM)
    db.straight(200)  # the left PWM (17) toggles the whole way: it must not select the IMU
    db.turn(90)
    true_heading = sim.physics.pose().heading_deg
    assert true_heading == pytest.approx(90.0, abs=0.5)
    assert imu.heading() == pytest.approx(true_heading, abs=0.5)
    db.close()


def test_the_baseline_imu_pins_are_refused_next_to_the_dc_motors_naming_the_pin(sim):
    from openbricks import pins
    from openbricks.drivers.icm45686 import ICM45686

    build_motors()
    baseline = rig.icm45686_spi("st3032")
    with pytest.raises(pins.ReservedPinError, match="GPIO 12 can't be used as ICM-45686 SPI SCK"):
        ICM45686(sck=baseline.sck, mosi=baseline.mosi, miso=baseline.miso, cs=baseline.cs)


def test_no_rig_pin_of_the_dc_build_is_a_motor_pin():
    motor_pins = {
        pin
        for channel in JGB37_CHANNELS
        for pin in (channel.in1, channel.in2, channel.enable, channel.encoder_a, channel.encoder_b)
    }
    imu = rig.icm45686_spi("jgb37")
    shared = {imu.sck, imu.mosi, imu.miso, imu.cs, rig.HCSR04_TRIG, rig.HCSR04_ECHO, 15, 16} & motor_pins
    assert not shared
    assert not {imu.sck, imu.mosi, imu.miso, imu.cs} & {38, 39, 14, 41, 48}  # buttons, UART, LED
