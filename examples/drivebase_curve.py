# SPDX-License-Identifier: MIT
"""Drive a rounded square with DriveBase.curve(): four straights joined by quarter-circle arcs.

The robot never stops to pivot: each straight flows into its arc with then="continue", so the lap
is one smooth motion. curve(radius, angle) follows Pybricks: a positive angle arcs right, the
radius sign picks forward or backward, and the outer wheel is capped at the straight_speed setting.

Run with:
    openbricks run -n <hub> examples/drivebase_curve.py
    openbricks sim run examples/drivebase_curve.py
"""

from openbricks.drivers.st3032 import ST3032Motor
from openbricks.robotics import DriveBase

LEFT_ID, RIGHT_ID = 1, 2
UART_ID, TX, RX = 1, 14, 41
WHEEL_DIAMETER_MM = 88
AXLE_TRACK_MM = 138

SIDE_MM = 200
RADIUS_MM = 100

left = ST3032Motor(servo_id=LEFT_ID, uart_id=UART_ID, tx=TX, rx=RX)
right = ST3032Motor(servo_id=RIGHT_ID, uart_id=UART_ID, tx=TX, rx=RX, invert=True)
db = DriveBase(left, right, wheel_diameter_mm=WHEEL_DIAMETER_MM, axle_track_mm=AXLE_TRACK_MM)
db.settings(straight_speed=300, turn_rate=200)

print("rounded square: %d mm sides, %d mm corner radius" % (SIDE_MM, RADIUS_MM))
for corner in range(4):
    db.straight(SIDE_MM, then="continue")
    last = corner == 3
    db.curve(radius=RADIUS_MM, angle=90, then="brake" if last else "continue")
print("done")
