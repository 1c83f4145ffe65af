"""The simulator builds the robot the program describes: wheels where its DriveBase puts them, the
build its motor drivers need, a colour sensor where it constructs one; and one line where the
program and a forced build disagree."""

import math

import pytest

from openbricks_sim.program_robot import infer_chassis
from openbricks_sim.run import ERROR, FINISHED, run_program

SERVO_SQUARE_CORNER = """
from openbricks.drivers.st3032 import ST3032Motor
from openbricks.robotics import DriveBase

left = ST3032Motor(servo_id={left_id}, uart_id=1, tx=14, rx=41, invert={left_invert})
right = ST3032Motor(servo_id={right_id}, uart_id=1, tx=14, rx=41, invert={right_invert})
db = DriveBase(left, right, wheel_diameter_mm=88, axle_track_mm=138)
db.straight(200)
{then}
"""

DC_CORNER = """
from openbricks.drivers.jgb37_520 import JGB37Motor
from openbricks.robotics import DriveBase

# The bridge channel on GPIO 9/10/11 (encoder 12/13) drives this robot's left wheel, mirrored.
left = JGB37Motor(in1=9, in2=10, pwm=11, encoder_a=12, encoder_b=13, invert=True)
right = JGB37Motor(in1=1, in2=2, pwm=17, encoder_a=7, encoder_b=8)
db = DriveBase(left, right, wheel_diameter_mm=65, axle_track_mm=120)
db.straight(200)
db.turn(90)
"""


def run(source, **kwargs):
    result = run_program("mission.py", source=source, **kwargs)
    assert result.exit == FINISHED, result.error or result.output
    return result


@pytest.mark.parametrize(
    "left_id, right_id, left_invert, right_invert",
    [(1, 2, False, True), (2, 1, True, False), (2, 1, False, True), (1, 2, True, False)],
)
def test_left_is_the_motor_the_drivebase_calls_left_and_invert_marks_the_mirrored_one(
    left_id, right_id, left_invert, right_invert
):
    source = SERVO_SQUARE_CORNER.format(
        left_id=left_id,
        right_id=right_id,
        left_invert=left_invert,
        right_invert=right_invert,
        then="db.turn(90)",
    )
    pose = run(source).pose
    assert pose["x_mm"] == pytest.approx(200.0, abs=5.0)
    assert pose["heading_deg"] == pytest.approx(90.0, abs=2.0)  # turn(90) is clockwise


def test_a_program_that_inverts_neither_wheel_spins_as_the_real_robot_would():
    source = SERVO_SQUARE_CORNER.format(left_id=2, right_id=1, left_invert=False, right_invert=False, then="")
    result = run_program("mission.py", source=source, limit_ms=8000)
    # The right servo is mounted mirrored whatever the program says: "straight" turns on the spot.
    assert abs(result.pose["x_mm"]) < 30.0
    assert abs(result.pose["heading_deg"]) > 45.0


def test_dc_wheels_are_the_motors_passed_to_drivebase_not_their_pins():
    result = run(DC_CORNER)
    assert result.job["chassis"] == "jgb37"  # no chassis given: the JGB37Motor drivers chose it
    assert result.pose["x_mm"] == pytest.approx(200.0, abs=5.0)
    assert result.pose["heading_deg"] == pytest.approx(90.0, abs=2.0)


def test_the_build_follows_the_motor_drivers_the_program_constructs():
    assert infer_chassis(DC_CORNER) == "jgb37"
    assert infer_chassis(SERVO_SQUARE_CORNER) == "st3032"
    assert infer_chassis("import time\ntime.sleep_ms(5)\n") == "st3032"
    assert infer_chassis("def broken(:\n") == "st3032"  # the run reports the syntax error itself


def test_a_forced_build_that_disagrees_with_the_program_says_so_in_one_line():
    result = run_program("mission.py", source=DC_CORNER, chassis="st3032", limit_ms=5000)
    assert result.exit == ERROR  # the servo chassis has nothing on those pins: the move is stuck
    notes = [line for line in result.output.splitlines() if line.startswith("sim:")]
    assert notes == [
        "sim: the program builds JGB37Motor motors but the simulated robot is the st3032 build "
        "(ST3032Motor / ST3215Motor); run it with --chassis jgb37 (or without --chassis, to let the "
        "program choose)"
    ]


BARE_COLOUR = """
from machine import I2C, Pin
from openbricks.drivers.tcs34725 import TCS34725

colour = TCS34725(I2C(0, sda=Pin(15), scl=Pin(16), freq=400_000))
print("ambient", colour.ambient())
"""


def test_a_bare_colour_sensor_against_a_forced_bare_part_says_so():
    # Without --bare-0x29 the sensor is wired where the program builds it (test_rig_options.py).
    result = run_program("mission.py", source=BARE_COLOUR, bare_0x29="vl53l0x")
    assert result.exit == ERROR  # the VL53L0X answers at 0x29, and the driver says it is not a TCS34725
    assert "not a TCS34725" in result.error
    assert result.output.startswith("sim: the program builds a TCS34725 straight on I2C0")


# The manual's DC build: its GPIO table (2.7), each motor built as its full-robot listing (5.6)
# builds them, neither inverted: a DC builder swaps the mirrored motor's leads instead.
DC_LISTING_SQUARE = """
from openbricks.drivers.jgb37_520 import JGB37Motor
from openbricks.robotics import DriveBase

LEFT_IN1, LEFT_IN2, LEFT_PWM = 1, 2, 17
LEFT_EA, LEFT_EB = 7, 8
RIGHT_IN1, RIGHT_IN2, RIGHT_PWM = 9, 10, 11
RIGHT_EA, RIGHT_EB = 12, 13

left = JGB37Motor(in1=LEFT_IN1, in2=LEFT_IN2, pwm=LEFT_PWM, encoder_a=LEFT_EA, encoder_b=LEFT_EB{left})
right = JGB37Motor(in1=RIGHT_IN1, in2=RIGHT_IN2, pwm=RIGHT_PWM, encoder_a=RIGHT_EA, encoder_b=RIGHT_EB{right})
db = DriveBase(left, right, wheel_diameter_mm=65, axle_track_mm=120)
for side in range(4):
    db.straight(300)
    db.turn(90)
print("odometry", db.distance(), db.angle())
"""


@pytest.mark.parametrize(
    "left, right",
    [("", ""), ("", ", invert=True"), (", invert=True", "")],
    ids=["manual-listing-neither-inverted", "right-inverted", "left-inverted"],
)
def test_a_dc_program_drives_its_300_mm_square_however_its_leads_are_wired(left, right):
    result = run(DC_LISTING_SQUARE.format(left=left, right=right))
    assert result.job["chassis"] == "jgb37"
    pose = result.pose
    assert math.hypot(pose["x_mm"], pose["y_mm"]) < 10.0
    assert abs((pose["heading_deg"] + 180.0) % 360.0 - 180.0) < 2.0
    assert "sim:" not in result.output  # the robot did what its program meant: nothing to point out


def test_a_straight_that_turns_in_place_names_the_mirrored_motor_in_one_line():
    source = SERVO_SQUARE_CORNER.format(
        left_id=1, right_id=2, left_invert=False, right_invert=False, then="db.straight(200)"
    )
    result = run_program("mission.py", source=source, limit_ms=15000)
    notes = [line for line in result.output.splitlines() if line.startswith("sim:")]
    assert len(notes) == 1, result.output  # once, though both straights spun
    assert notes[0].startswith("sim: straight(200) turned the robot in place (")
    assert notes[0].endswith(
        "instead of driving it: a motor mounted mirrored is likely not inverted; build the right-hand "
        "motor with invert=True (and only that one)"
    )


def test_a_correct_program_gets_no_note_however_far_it_drives():
    source = SERVO_SQUARE_CORNER.format(
        left_id=1, right_id=2, left_invert=False, right_invert=True, then="db.turn(90)\ndb.straight(-300)"
    )
    result = run(source)
    assert "sim:" not in result.output
