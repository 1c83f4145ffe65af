# SPDX-License-Identifier: MIT
"""One TCS34725 colour sensor wired straight to the hub's I2C bus (SDA 15, SCL 16), no multiplexer.

A robot with a single colour sensor needs no TCA9548A: the sensor answers at its fixed address
0x29. This program reads the mat under the robot, then drives 400 mm and says where the sensor
crossed onto a dark line and off it again: reflection() is 0 on black and 100 on white. It moves
with wait=False and polls done(), so it reads the sensor while the wheels turn.

Run with:
    openbricks sim run examples/colour_bare_bus.py --world zones
"""

import time

from machine import I2C, Pin

from openbricks.drivers.st3032 import ST3032Motor
from openbricks.drivers.tcs34725 import TCS34725
from openbricks.robotics import DriveBase

DARK_BELOW = 40  # reflection under this is the line

colour = TCS34725(I2C(0, sda=Pin(15), scl=Pin(16), freq=400_000))  # wired straight to I2C0

left = ST3032Motor(servo_id=1, uart_id=1, tx=14, rx=41)
right = ST3032Motor(servo_id=2, uart_id=1, tx=14, rx=41, invert=True)
db = DriveBase(left, right, wheel_diameter_mm=88, axle_track_mm=138)

r, g, b = colour.rgb()
print("start: reflection %d, rgb %d %d %d" % (colour.reflection(), r, g, b))
on_line = False
db.straight(400, wait=False)
while not db.done():
    dark = colour.reflection() < DARK_BELOW
    if dark != on_line:
        on_line = dark
        print("%s at %d mm" % ("onto the line" if dark else "off the line", db.distance()))
    time.sleep_ms(5)
print("done")
