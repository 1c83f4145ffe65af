# SPDX-License-Identifier: MIT
"""A square on the BNO055's heading: the I2C IMU the manual's hardware guide (2.4) wires straight to
the bus at 0x28, used as the DriveBase gyro (manual 8.2: for an I2C IMU, a Python outer loop).

Run with:
    openbricks sim run examples/bno055_square.py
"""

from machine import I2C, Pin

from openbricks.drivers.bno055 import BNO055
from openbricks.drivers.st3032 import ST3032Motor
from openbricks.robotics import DriveBase

imu = BNO055(I2C(0, sda=Pin(15), scl=Pin(16), freq=400_000))
left = ST3032Motor(servo_id=1, uart_id=1, tx=14, rx=41)
right = ST3032Motor(servo_id=2, uart_id=1, tx=14, rx=41, invert=True)
db = DriveBase(left, right, wheel_diameter_mm=88, axle_track_mm=138, imu=imu)
db.use_gyro(True)

for side in range(4):
    db.straight(300)
    db.turn(90)
    print("corner %d: heading %.1f" % (side + 1, imu.heading()))
db.stop(then="brake")
print("done")
