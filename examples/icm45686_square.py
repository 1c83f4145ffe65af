# SPDX-License-Identifier: MIT
"""The same square twice, encoders only and then gyro-corrected, with each pass's heading drift.

The ICM-45686 learns its gyro bias while the robot stands still (about half a second), then
use_gyro(True) makes the drive base steer by measured body rotation, so wheel slip no longer
turns into heading error. save_calibration() keeps the learned bias in NVS for the next boot.

Wiring: the breakout on 3V3/GND and SPI SCK 12, MOSI 13, MISO 11, CS 17; INT stays unwired.
Needs about 0.5 m of clear floor.

Run with:
    openbricks run -n <hub> examples/icm45686_square.py
    openbricks sim run examples/icm45686_square.py
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
SIDE_MM = 300


def square_drift(db, imu):
    """Drive one square and return how far the heading ended from a whole turn, in degrees."""
    start = imu.heading()
    for corner in range(4):
        db.straight(SIDE_MM)
        db.turn(90)
        print("corner %d: heading %+.1f" % (corner + 1, imu.heading() - start))
    time.sleep_ms(300)  # let the chassis settle before the final reading
    return imu.heading() - start - 360


print("hold still: learning the gyro bias ...")
imu = ICM45686(sck=SCK, mosi=MOSI, miso=MISO, cs=CS)
while not imu.calibrated():
    time.sleep_ms(100)
imu.save_calibration()

left = ST3032Motor(servo_id=LEFT_ID, uart_id=UART_ID, tx=TX, rx=RX)
right = ST3032Motor(servo_id=RIGHT_ID, uart_id=UART_ID, tx=TX, rx=RX, invert=True)
db = DriveBase(left, right, wheel_diameter_mm=WHEEL_DIAMETER_MM, axle_track_mm=AXLE_TRACK_MM, imu=imu)
db.settings(straight_speed=300, turn_rate=200)

print("pass 1: encoders only")
print("drift: %+.2f deg" % square_drift(db, imu))
db.use_gyro(True)
print("pass 2: gyro-corrected")
print("drift: %+.2f deg" % square_drift(db, imu))
db.stop(then="brake")
