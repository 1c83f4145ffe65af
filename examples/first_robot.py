# SPDX-License-Identifier: MIT
"""A first program for the standard robot: out 500 mm, turn round, back home.

Two ST-3032 servos drive the wheels (ids 1 and 2 on the serial bus, UART1 TX 14 / RX 41); the
right one is mounted mirrored, so it is built with invert=True. Distances are millimetres, turns
are degrees of the robot's heading, positive to the right.

Run with:
    openbricks sim run examples/first_robot.py
    openbricks run -n RobotA examples/first_robot.py
"""

from openbricks.drivers.st3032 import ST3032Motor
from openbricks.robotics import DriveBase

left = ST3032Motor(servo_id=1, uart_id=1, tx=14, rx=41)
right = ST3032Motor(servo_id=2, uart_id=1, tx=14, rx=41, invert=True)
db = DriveBase(left, right, wheel_diameter_mm=88, axle_track_mm=138)

db.straight(500)  # forward 500 mm
db.turn(180)  # turn round, to the right
db.straight(500)  # and back
print("home again after %.0f mm" % db.distance())
