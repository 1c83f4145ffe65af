"""Program boundaries on a robot whose DriveBase adopted its serial-bus wheels: every run gets the bus
back, and a run that ends mid-drive leaves the wheels released."""

import machine

from fakes import tmpdir
from fakes.scs_servo import FakeServo, ScsBus
from openbricks import launcher, log

NEEDS_NATIVE = True

_BUILD = (
    "from openbricks.drivers.st3032 import ST3032Motor\n"
    "from openbricks.robotics import DriveBase\n"
    "left = ST3032Motor(servo_id=1)\n"
    "right = ST3032Motor(servo_id=2, invert=True)\n"
    "db = DriveBase(left, right, wheel_diameter_mm=56, axle_track_mm=114)\n"
)


def _robot(directory, source):
    bus = ScsBus()
    for servo_id in (1, 2):
        bus.add(FakeServo(servo_id))
    machine.board.attach_uart(1, bus)
    with open(directory + "/program.py", "w") as f:
        f.write(source)
    hub = launcher.Launcher(39, directory + "/program.py", log_dir=directory + "/logs")
    hub.start_watcher(0)
    return hub, bus


def test_a_serial_bus_drivebase_program_runs_again_after_it_finished():
    with tmpdir.scratch() as directory:
        hub, _bus = _robot(directory, _BUILD + "db.straight(30)\nprint('arrived')\n")
        for index in range(3):
            outcome = hub.run_program("host run", reraise_interrupt=False)
            assert outcome == "finished", log.read_run(index, directory + "/logs")
            assert "arrived" in log.read_run(index, directory + "/logs")


def test_a_program_that_fails_mid_drive_leaves_the_wheels_free():
    with tmpdir.scratch() as directory:
        hub, bus = _robot(
            directory,
            _BUILD + "db.drive(150, 0)\nwait_ms = 300\nimport time\n"
            "time.sleep_ms(wait_ms)\nraise ValueError('lost the line')\n",
        )
        assert hub.run_program("host run") == "error"
        assert "ValueError: lost the line" in log.read_run(0, directory + "/logs")
        for servo_id in (1, 2):
            assert not bus.servo(servo_id).torque_enabled, "servo %d still drives its wheel" % servo_id
