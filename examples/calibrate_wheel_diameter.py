# SPDX-License-Identifier: MIT
"""Step 1 of drive base calibration: the wheel diameter, from one long straight drive.

Mark the floor at a reference point of the robot (the axle centre, say), run this, and measure
how far that point really travelled. The robot drives COMMANDED_MM on the diameter below; if it
went farther the wheels are larger than configured, and vice versa:

    new diameter = WHEEL_DIAMETER_MM * measured_mm / COMMANDED_MM

Repeat once with the new value: the drive should then land within a few millimetres. Calibrate
on the surface you compete on (soft tyres squash differently on carpet, foam and wood), then go
on to the axle track (examples/icm45686_axle_track.py).

Run with:
    openbricks run -n <hub> examples/calibrate_wheel_diameter.py
"""

import math

from openbricks.drivers.st3032 import ST3032Motor
from openbricks.robotics import DriveBase

LEFT_ID, RIGHT_ID = 1, 2
UART_ID, TX, RX = 1, 14, 41
WHEEL_DIAMETER_MM = 88
AXLE_TRACK_MM = 138
COMMANDED_MM = 1000

left = ST3032Motor(servo_id=LEFT_ID, uart_id=UART_ID, tx=TX, rx=RX)
right = ST3032Motor(servo_id=RIGHT_ID, uart_id=UART_ID, tx=TX, rx=RX, invert=True)
db = DriveBase(left, right, wheel_diameter_mm=WHEEL_DIAMETER_MM, axle_track_mm=AXLE_TRACK_MM)
db.settings(straight_speed=150)

start = (left.angle(), right.angle())
db.straight(COMMANDED_MM, then="brake")
db.stop(then="brake", wait=True)
turned = ((left.angle() - start[0]) + (right.angle() - start[1])) / 2
print(
    "commanded %d mm; the wheels turned %.1f deg (%.1f mm at %s mm diameter)"
    % (COMMANDED_MM, turned, turned / 360 * math.pi * WHEEL_DIAMETER_MM, WHEEL_DIAMETER_MM)
)
print("measure the distance travelled, then:")
print("  new wheel_diameter_mm = %s * measured_mm / %d" % (WHEEL_DIAMETER_MM, COMMANDED_MM))
