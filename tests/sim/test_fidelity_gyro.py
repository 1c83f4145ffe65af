"""The gyro square (examples/icm45686_square.py, manual 5.2) judged by the robot's true heading.

The example reports each pass's drift as the IMU itself measures it. These tests measure the robot's
actual rotation from the physics instead, so an IMU whose integral runs away from the body cannot
pass by agreeing with itself. The product bar: the gyro-corrected square drifts under 1 degree total.

Everything runs through the unchanged runtime: ICM45686 on SPI (SCK 12, MOSI 13, MISO 11, CS 17),
ST3032Motor wheels adopted by openbricks.robotics.DriveBase, settings as in the example.
"""

import pytest

from openbricks_sim.shim import Shim
from openbricks_sim.simulation import Simulation

SIDE_MM = 300
TRUE_AXLE_TRACK_MM = 138  # the simulated st3032 chassis


def heading_change_deg(start, end):
    return (end - start + 180.0) % 360.0 - 180.0


def gyro_square(gyro, axle_track_mm=TRUE_AXLE_TRACK_MM, sample_hz=None):
    """Drive the example's square once; returns (true drift, IMU-reported drift), in degrees.

    sample_hz None keeps the driver's default sampling rate.
    """
    sim = Simulation("empty", "st3032", epoch_ms=0)
    try:
        with Shim(sim):
            import time

            from openbricks.drivers.icm45686 import ICM45686
            from openbricks.drivers.st3032 import ST3032Motor
            from openbricks.robotics import DriveBase

            options = {} if sample_hz is None else {"sample_hz": sample_hz}
            imu = ICM45686(sck=12, mosi=13, miso=11, cs=17, **options)
            while not imu.calibrated():
                time.sleep_ms(100)
            db = DriveBase(
                ST3032Motor(1),
                ST3032Motor(2, invert=True),
                wheel_diameter_mm=88,
                axle_track_mm=axle_track_mm,
                imu=imu,
            )
            db.settings(straight_speed=300, turn_rate=200)
            db.use_gyro(gyro)
            true_start, imu_start = sim.physics.pose().heading_deg, imu.heading()
            for _ in range(4):
                db.straight(SIDE_MM)
                db.turn(90)
            time.sleep_ms(300)  # settled, as the example waits before its final reading
            true_drift = heading_change_deg(true_start, sim.physics.pose().heading_deg)
            imu_drift = imu.heading() - imu_start - 360.0
            db.close()
            imu.close()
        return true_drift, imu_drift
    finally:
        sim.close()


def test_the_gyro_square_closes_within_a_degree_of_true_heading():
    # At the driver's default 200 Hz sampling; the IMU reports the body's average rate over each
    # sample (regression: an instantaneous rate aliased with the heading loop and drifted -2.7 deg).
    true_drift, imu_drift = gyro_square(gyro=True)
    assert abs(true_drift) < 1.0, f"the robot turned {true_drift:+.2f} deg away from its start heading"
    assert imu_drift == pytest.approx(true_drift, abs=0.1)


def test_without_the_gyro_in_the_loop_the_imu_follows_the_body():
    true_drift, imu_drift = gyro_square(gyro=False)
    assert imu_drift == pytest.approx(true_drift, abs=0.1)


def test_sampled_at_the_control_rate_the_gyro_square_closes_within_a_degree():
    true_drift, imu_drift = gyro_square(gyro=True, sample_hz=1000)
    assert abs(true_drift) < 1.0
    assert imu_drift == pytest.approx(true_drift, abs=0.1)


def test_the_gyro_steers_out_a_miscalibrated_axle_track():
    # The program believes the wheels are 150 mm apart; they are 138 mm. Turning by the encoders,
    # each 90 deg turn comes out ~8 deg long; turning by the gyro, the square still closes.
    encoders_only, _ = gyro_square(gyro=False, axle_track_mm=150, sample_hz=1000)
    by_gyro, _ = gyro_square(gyro=True, axle_track_mm=150, sample_hz=1000)
    assert abs(encoders_only) > 20.0
    assert abs(by_gyro) < 1.0
