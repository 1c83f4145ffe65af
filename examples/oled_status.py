# SPDX-License-Identifier: MIT
"""Show the robot's odometry on an SSD1306 OLED (128x64, I2C 0x3C on the I2C0 bus) while it drives
a square.

Wiring: the OLED's SDA/SCL on GPIO 15/16 beside the sensors (manual 2.4), VCC on 3V3.

Run with:
    openbricks run -n <hub> examples/oled_status.py
    openbricks sim run examples/oled_status.py
"""

from machine import I2C, Pin

from openbricks.drivers.ssd1306 import SSD1306
from openbricks.drivers.st3032 import ST3032Motor
from openbricks.robotics import DriveBase

oled = SSD1306(I2C(0, sda=Pin(15), scl=Pin(16), freq=400_000))
left = ST3032Motor(servo_id=1, uart_id=1, tx=14, rx=41)
right = ST3032Motor(servo_id=2, uart_id=1, tx=14, rx=41, invert=True)
db = DriveBase(left, right, wheel_diameter_mm=88, axle_track_mm=138)


def show(title):
    oled.fill(0)
    oled.text(title, 0, 0)
    oled.text("dist %5d mm" % db.distance(), 0, 16)
    oled.text("turn %5d deg" % db.angle(), 0, 28)
    oled.rect(0, 44, 128, 20, 1)
    oled.show()


for side in range(4):
    show("side %d" % (side + 1))
    db.straight(200)
    db.turn(90)
show("done")
print("done: %.0f mm, %.0f deg" % (db.distance(), db.angle()))
