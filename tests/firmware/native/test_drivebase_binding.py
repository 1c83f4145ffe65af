"""openbricks_native.DriveBase as Python sees it: arguments, errors, and the IO-callable path."""

import math

import pytest

import openbricks_native as native
from tests.firmware.native.drivebase_rig import AXLE_TRACK_MM, WHEEL_DIAMETER_MM, Chassis


def test_settings_default_to_the_manual_and_read_back():
    db = native.DriveBase(WHEEL_DIAMETER_MM, AXLE_TRACK_MM)
    straight_speed, turn_rate, acceleration, turn_acceleration = db.settings()
    assert (acceleration, turn_acceleration) == (1500.0, 1500.0)
    assert straight_speed > 0 and turn_rate > 0
    db.settings(turn_rate=120)
    assert db.settings() == (straight_speed, 120.0, 1500.0, 1500.0), "unnamed settings must be kept"
    db.settings(straight_speed=250, turn_rate=200, acceleration=1000, turn_acceleration=800)
    assert db.settings() == (250.0, 200.0, 1000.0, 800.0)


@pytest.mark.parametrize(
    ("kwargs", "error", "message"),
    [
        ({"straight_speed": 0}, ValueError, "straight_speed must be > 0 wheel-deg/s"),
        ({"acceleration": -5}, ValueError, "acceleration must be > 0"),
        ({"turn_rate": math.nan}, ValueError, "turn_rate must be a finite number"),
        ({"turn_acceleration": "fast"}, TypeError, "turn_acceleration must be a number"),
    ],
)
def test_bad_settings_are_refused_by_name_and_change_nothing(kwargs, error, message):
    db = native.DriveBase(WHEEL_DIAMETER_MM, AXLE_TRACK_MM)
    before = db.settings()
    with pytest.raises(error, match=message):
        db.settings(**kwargs)
    assert db.settings() == before


@pytest.mark.parametrize(
    ("args", "message"),
    [
        ((0, 114), "wheel_diameter_mm must be > 0 mm"),
        ((56, -1), "axle_track_mm must be > 0 mm"),
        ((math.inf, 114), "wheel_diameter_mm must be a finite number"),
    ],
)
def test_bad_geometry_is_refused(args, message):
    with pytest.raises(ValueError, match=message):
        native.DriveBase(*args)


def test_io_callables_come_as_a_full_set_or_not_at_all():
    with pytest.raises(TypeError, match="coast_right is missing"):
        native.DriveBase(
            56, 114, read_left=float, read_right=float, write_left=print, write_right=print, coast_left=print
        )
    with pytest.raises(TypeError, match="read_left must be callable"):
        native.DriveBase(56, 114, read_left=3)


@pytest.mark.parametrize("then", ["coast", "stop", "brake", "hold", "continue"])
def test_every_then_value_of_the_manual_is_accepted(then):
    db = native.DriveBase(56, 114)
    db.straight(100, then=then)
    db.turn(90, then=then)
    db.curve(radius=150, angle=90, then=then)
    db.stop(then=then)


def test_an_unknown_then_names_the_accepted_values():
    db = native.DriveBase(56, 114)
    with pytest.raises(ValueError, match="'coast' \\(or 'stop'\\), 'brake', 'hold', 'continue'; got 'park'"):
        db.straight(100, then="park")


def test_non_finite_distances_are_refused_before_anything_moves():
    db = native.DriveBase(56, 114)
    with pytest.raises(ValueError, match="distance_mm must be a finite number"):
        db.straight(math.nan)
    with pytest.raises(TypeError, match="radius \\(mm\\) must be a number"):
        db.curve("wide", 90)
    assert db.done()


@pytest.mark.parametrize(
    ("command", "message"),
    [
        (lambda db: db.straight(1e39), "distance_mm is beyond the float range"),
        (lambda db: db.straight(2e38), r"straight\(\): the values are too large"),
        (lambda db: db.turn(3e38), r"turn\(\): the values are too large"),
        (lambda db: db.curve(1e38, 1e38), r"curve\(\): the values are too large"),
        (lambda db: db.drive(3e38, 0), r"drive\(\): the values are too large"),
        (lambda db: db.move_wheels(3e38, 3e38), r"move_wheels\(\): the values are too large"),
    ],
)
def test_magnitudes_that_overflow_the_controller_are_refused_not_ignored(command, message):
    # Finite in Python, but infinite once in float wheel-degrees: the core refuses the command, and
    # the caller must hear about it instead of a robot that silently does nothing.
    db = native.DriveBase(56, 114)
    db.update(0, 0.0, 0.0)
    with pytest.raises(ValueError, match=message):
        command(db)
    assert db.done() and db.update(1, 0.0, 0.0) == (None, None), "nothing was armed"


def test_update_takes_readings_or_none_and_checks_its_arguments():
    db = native.DriveBase(56, 114)
    assert db.update(0, 0.0, 0.0) == (None, None), "idle: both wheels released"
    assert db.update(1, None, 0.0) == (None, None)
    with pytest.raises(TypeError, match="takes 3 or 4 arguments, got 2"):
        db.update(2, 0.0)
    with pytest.raises(TypeError, match="left_deg must be degrees"):
        db.update(2, "0", 0.0)
    db.use_gyro(True)
    with pytest.raises(TypeError, match="pass heading_deg"):
        db.update(3, 0.0, 0.0)
    assert db.update(3, 0.0, 0.0, 12.5) == (None, None)


def test_a_drivebase_without_io_cannot_be_ticked_natively():
    db = native.DriveBase(56, 114)
    with pytest.raises(ValueError, match="use update"):
        db.tick(0)
    with pytest.raises(ValueError, match="no IO to tick"):
        native.MotorProcess().subscribe(db)


class WiredChassis:
    """The rig's chassis behind IO callables, as a hub runtime would wire real motors."""

    def __init__(self):
        self.chassis = Chassis()
        self.duties = [None, None]
        self.coast_calls = 0
        self.fail_reads = None

    def reader(self, side):
        def read():
            if self.fail_reads is not None:
                raise self.fail_reads
            return self.chassis.wheels[side].encoder_deg

        return read

    def writer(self, side):
        def write(duty):
            self.duties[side] = duty

        return write

    def coaster(self, side):
        def coast():
            self.duties[side] = None
            self.coast_calls += 1

        return coast

    def drivebase(self, **kwargs):
        return native.DriveBase(
            WHEEL_DIAMETER_MM,
            AXLE_TRACK_MM,
            read_left=self.reader(0),
            read_right=self.reader(1),
            write_left=self.writer(0),
            write_right=self.writer(1),
            coast_left=self.coaster(0),
            coast_right=self.coaster(1),
            **kwargs,
        )

    def step(self):
        self.chassis.step(tuple(self.duties), 0.001)


def test_motor_process_ticks_a_drivebase_natively_through_its_io_callables():
    wired = WiredChassis()
    db = wired.drivebase()
    process = native.MotorProcess()
    process.subscribe(db)
    db.straight(200)
    now = 0
    while not db.done():
        process.tick(now)
        wired.step()
        now += 1
        assert now < 5000
    for _ in range(300):
        process.tick(now)
        wired.step()
        now += 1
    assert wired.chassis.x_mm == pytest.approx(200, abs=1.0)
    assert wired.duties == [None, None], "then='coast' released both wheels through coast_*()"


def test_an_idle_drivebase_leaves_the_wheels_to_whoever_drives_them():
    # After a coasting end, the drive base keeps ticking (odometry) but writes nothing more: a
    # motor driven directly afterwards (its own servo, dc()) is not released again every period.
    wired = WiredChassis()
    db = wired.drivebase()
    process = native.MotorProcess()
    process.subscribe(db)
    db.straight(100)
    now = 0
    while not db.done():
        process.tick(now)
        wired.step()
        now += 1
        assert now < 5000
    process.tick(now)
    calls = wired.coast_calls
    wired.duties[0] = 50.0  # another controller drives the left wheel
    for later in range(now + 1, now + 500):
        process.tick(later)
        wired.step()
    assert wired.coast_calls == calls, f"{wired.coast_calls - calls} coast writes while idle"
    assert wired.duties == [50.0, None]


def test_coast_stop_releases_both_wheels_inside_the_call():
    wired = WiredChassis()
    db = wired.drivebase()
    db.drive(100, 0)
    for now in range(200):
        db.tick(now)
        wired.step()
    calls = wired.coast_calls
    db.stop()
    assert wired.coast_calls == calls + 2 and wired.duties == [None, None]


def test_an_io_error_surfaces_from_the_tick_and_the_watchdog_still_halts():
    wired = WiredChassis()
    db = wired.drivebase()
    db.drive(100, 0)
    for now in range(100):
        db.tick(now)
        wired.step()
    wired.fail_reads = OSError("bus timeout")
    for now in range(100, 130):
        with pytest.raises(OSError, match="bus timeout"):
            db.tick(now)  # every period reports the error to the caller ...
    # ... and a read that raised is a missing reading: past the watchdog both wheels are released.
    assert db.fault() == ("left", "right")
    assert wired.duties == [None, None]


def test_use_gyro_needs_a_heading_source_when_io_is_wired():
    wired = WiredChassis()
    db = wired.drivebase()
    with pytest.raises(ValueError, match="heading=<callable"):
        db.use_gyro(True)
    db = wired.drivebase(heading=lambda: wired.chassis.heading_deg)
    db.use_gyro(True)
    db.turn(45)
    now = 0
    while not db.done():
        db.tick(now)
        wired.step()
        now += 1
        assert now < 5000
    assert wired.chassis.heading_deg == pytest.approx(45, abs=0.2)
