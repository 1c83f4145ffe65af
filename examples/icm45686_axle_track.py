# SPDX-License-Identifier: MIT
"""Step 2 of drive base calibration: the axle track, measured by the gyro.

The drive base turns TURNS full turns in place on its encoders alone (the gyro does not steer:
the point is to see what the encoders produce), while the ICM-45686 measures the rotation that
really happened. If the robot turned too far, the real track is smaller than configured:

    new axle track = AXLE_TRACK_MM * commanded_deg / measured_deg

Ten turns make each 0.1 degree of gyro error worth 0.003 % of track. Calibrate the wheel
diameter first (examples/calibrate_wheel_diameter.py): the turn uses it too.

Run with:
    openbricks run -n <hub> examples/icm45686_axle_track.py
    openbricks sim run examples/icm45686_axle_track.py
"""

import time

from openbricks.drivers.icm45686 import ICM45686
from openbricks.drivers.st3032 import ST3032Motor
from openbricks.robotics import DriveBase

LEFT_ID, RIGHT_ID = 1, 2
UART_ID, TX, RX = 1, 14, 41
SCK, MOSI, MISO, CS = 12, 13, 11, 17
WHEEL_DIAMETER_MM = 88
AXLE_TRACK_MM = 138
TURNS = 10

print("hold still: learning the gyro bias ...")
imu = ICM45686(sck=SCK, mosi=MOSI, miso=MISO, cs=CS)
while not imu.calibrated():
    time.sleep_ms(100)
left = ST3032Motor(servo_id=LEFT_ID, uart_id=UART_ID, tx=TX, rx=RX)
right = ST3032Motor(servo_id=RIGHT_ID, uart_id=UART_ID, tx=TX, rx=RX, invert=True)
db = DriveBase(left, right, wheel_diameter_mm=WHEEL_DIAMETER_MM, axle_track_mm=AXLE_TRACK_MM, imu=imu)
db.settings(turn_rate=120)

commanded = 360 * TURNS
start = imu.heading()
db.turn(commanded, then="brake")
time.sleep_ms(500)  # let the chassis come to rest before the final reading
measured = imu.heading() - start
print("commanded %d deg, the gyro measured %.1f deg" % (commanded, measured))
print("axle_track_mm = %.1f  (was %s)" % (AXLE_TRACK_MM * commanded / measured, AXLE_TRACK_MM))
