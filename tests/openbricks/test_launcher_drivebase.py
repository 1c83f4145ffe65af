"""Program boundaries on a robot whose DriveBase adopted its serial-bus wheels: every run gets the bus
back, and a run that ends mid-drive leaves the wheels released."""

import machine

from fakes import tmpdir
from fakes.scs_servo import FakeServo, ScsBus
from openbricks import launcher, log, pins
from tests.openbricks.test_launcher import _hub, _log_lines, _stage

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


def test_the_next_program_can_rewire_the_servo_bus_the_last_one_used():
    with tmpdir.scratch() as directory:
        bus = ScsBus()
        bus.add(FakeServo(1))
        machine.board.attach_uart(1, bus)
        motor = "from openbricks.drivers.st3032 import ST3032Motor\nST3032Motor(servo_id=1, rx=%d)\n"
        hub = _hub(directory, motor % 41)
        assert hub.run_program() == "finished"
        # The adapter moved to the old RX pin (the manual's 2.5 wiring): the finished program's bus
        # must not hold UART1 to its wiring.
        _stage(directory, motor % 6)
        assert hub.run_program() == "finished", "\n".join(_log_lines(directory))
        assert pins.owner_of(41) is None and pins.owner_of(6) is None
