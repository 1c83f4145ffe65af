# SPDX-License-Identifier: MIT
"""Drive a square with the ST-3032 drive base: four sides of SIDE_MM, each followed by a 90 degree
right turn.

With WHEEL_DIAMETER_MM and AXLE_TRACK_MM calibrated (examples/calibrate_wheel_diameter.py, then
examples/icm45686_axle_track.py), the robot ends within a centimetre or so of where it started.
Moves end with then="coast" (the default): the wheels free-wheel for a moment between segments.
Pass then="brake" to stop actively, or then="hold" to lock the wheels in place.

Run with:
    openbricks run -n <hub> examples/drivebase_square.py
    openbricks sim run examples/drivebase_square.py
"""

from openbricks.drivers.st3032 import ST3032Motor
from openbricks.robotics import DriveBase

LEFT_ID, RIGHT_ID = 1, 2
UART_ID, TX, RX = 1, 14, 41
WHEEL_DIAMETER_MM = 88
AXLE_TRACK_MM = 138

SIDE_MM = 300
LAPS = 1
STRAIGHT_SPEED = 300  # wheel-deg/s
TURN_RATE = 200  # wheel-deg/s

left = ST3032Motor(servo_id=LEFT_ID, uart_id=UART_ID, tx=TX, rx=RX)
right = ST3032Motor(servo_id=RIGHT_ID, uart_id=UART_ID, tx=TX, rx=RX, invert=True)
db = DriveBase(left, right, wheel_diameter_mm=WHEEL_DIAMETER_MM, axle_track_mm=AXLE_TRACK_MM)
db.settings(straight_speed=STRAIGHT_SPEED, turn_rate=TURN_RATE)

print("square: %d mm sides, %d lap(s)" % (SIDE_MM, LAPS))
for lap in range(LAPS):
    for side in range(4):
        print("lap %d side %d" % (lap + 1, side + 1))
        db.straight(SIDE_MM)
        db.turn(90)
db.stop(then="brake")
print("done")
