"""A DriveBase steering by the firmware's ICM-45686 driver: the heading is read in C, not from Python.

On the image, ICM45686 hands its chip to `_openbricks_native.ICM45686` (firmware/native/icm45686.c on
the ESP32's SPI) and the hard tick takes one burst per millisecond. Here the real C driver talks to
the fake board's chip through a transfer callable, and a 1 ms timer stands in for the hard tick's
poll; everything else (the driver, the drive base, the controller) is what the hub runs.
"""

import time

import _openbricks_native
import machine
from machine import Timer

from fakes.expect import approx
from openbricks import timers
from openbricks.drivers import icm45686
from tests.openbricks.robotics.robots import EncoderRobot

NEEDS_NATIVE = True


class HubChip:
    """The firmware's ICM45686 constructor, reaching the chip on the fake board instead of the SPI."""

    def __init__(self):
        self.built = []
        self.hard_tick = None

    def __call__(self, sck, mosi, miso, cs, hz, mode, spi_id, scale):
        wire = machine.board.spi_devices[cs].transfer
        chip = _openbricks_native.ICM45686(wire, delay_ms=time.sleep_ms, scale=scale)
        self.built.append(((sck, mosi, miso, cs, hz, mode, spi_id), chip))
        # The hard tick's poll: one burst every millisecond, whatever Python does.
        self.hard_tick = Timer(timers.IMU)
        self.hard_tick.init(mode=Timer.PERIODIC, period=1, callback=lambda _t: chip.sample(time.ticks_us()))
        return chip


def _gyro_robot_on_the_hub(slip):
    hub = HubChip()
    saved = icm45686._hub_chip
    icm45686._hub_chip = lambda: hub
    try:
        robot = EncoderRobot(gyro=True, slip=slip)
    finally:
        icm45686._hub_chip = saved
    return robot, hub


def test_the_driver_hands_its_chip_to_the_native_driver_and_takes_no_timer():
    robot, hub = _gyro_robot_on_the_hub((0.0, 0.0))
    try:
        ((wiring, chip),) = hub.built
        assert wiring == (4, 5, 6, 15, 8_000_000, 3, 1)
        assert robot.imu.native_heading() is chip
        assert robot.imu._timer is None
        assert robot.imu.stats()[2] is True
    finally:
        hub.hard_tick.deinit()
        robot.close()


def test_the_drive_base_steers_through_wheel_slip_by_the_heading_read_in_c():
    robot, hub = _gyro_robot_on_the_hub((0.05, 0.0))
    try:
        db = robot.drivebase()

        def python_heading():
            raise AssertionError("the drive base called the IMU's Python heading()")

        robot.imu.heading = python_heading  # the controller must not call it: it reads the chip in C
        db.use_gyro(True)
        db.straight(500)
        assert approx(robot.chassis.heading_deg, 0, 1)
        assert approx(db.distance(), 500, 5)
        reads_ok, read_errors, _ = robot.imu.stats()
        assert reads_ok > 1000 and read_errors == 0
    finally:
        hub.hard_tick.deinit()
        robot.close()


def test_a_finished_programs_chip_is_closed_when_the_next_one_builds_an_imu():
    from openbricks import pins

    robot, hub = _gyro_robot_on_the_hub((0.0, 0.0))
    hub.hard_tick.deinit()
    (_, first) = hub.built[0]
    pins.reset_claims()  # what the launcher does with a finished program's claims
    robot2, hub2 = _gyro_robot_on_the_hub((0.0, 0.0))
    try:
        assert first.stats()[2] is False  # closed: it no longer holds the SPI device
        assert hub2.built[0][1].stats()[2] is True
    finally:
        hub2.hard_tick.deinit()
        robot2.close()
