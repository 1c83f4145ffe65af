# SPDX-License-Identifier: MIT
"""A whole robot: drive forward on the gyro until the colour sensor sees red, then turn back.

The baseline build: two ST-3032 wheels on the serial bus, an ICM-45686 on SPI steering the
drive base by measured rotation, and a TCS34725 behind a TCA9548A (channel 0, front left).
The robot reports the colour under it and its heading while it drives, stops on red, and turns
round to face where it came from.

Run with:
    openbricks run -n <hub> examples/full_robot.py
    openbricks sim run examples/full_robot.py --world zones
"""

import time

from machine import I2C, Pin

from openbricks.drivers.icm45686 import ICM45686
from openbricks.drivers.st3032 import ST3032Motor
from openbricks.drivers.tca9548a import TCA9548A
from openbricks.drivers.tcs34725 import TCS34725
from openbricks.robotics import DriveBase

LEFT_ID, RIGHT_ID = 1, 2
UART_ID, TX, RX = 1, 14, 41
SCK, MOSI, MISO, CS = 12, 13, 11, 17
WHEEL_DIAMETER_MM = 88
AXLE_TRACK_MM = 138
SPEED_MM_S = 150
REPORT_EVERY_MS = 250
TIMEOUT_MS = 20_000


def is_red(rgb):
    r, g, b = rgb
    return r > 150 and r > 2 * g and r > 2 * b


imu = ICM45686(sck=SCK, mosi=MOSI, miso=MISO, cs=CS)
while not imu.calibrated():  # keep still while the gyro learns its bias
    time.sleep_ms(50)
mux = TCA9548A(I2C(0, sda=Pin(15), scl=Pin(16), freq=400_000))
colour = TCS34725(mux[0])
left = ST3032Motor(servo_id=LEFT_ID, uart_id=UART_ID, tx=TX, rx=RX)
right = ST3032Motor(servo_id=RIGHT_ID, uart_id=UART_ID, tx=TX, rx=RX, invert=True)
db = DriveBase(left, right, wheel_diameter_mm=WHEEL_DIAMETER_MM, axle_track_mm=AXLE_TRACK_MM, imu=imu)
db.use_gyro(True)

start = time.ticks_ms()
last_report = start - REPORT_EVERY_MS
db.drive(SPEED_MM_S, 0)
while True:
    rgb = colour.rgb()
    now = time.ticks_ms()
    if time.ticks_diff(now, last_report) >= REPORT_EVERY_MS:
        print("rgb=(%3d,%3d,%3d) heading=%+6.1f" % (rgb[0], rgb[1], rgb[2], imu.heading()))
        last_report = now
    if is_red(rgb):
        db.stop(then="brake")
        print("red after %d ms: turning back" % time.ticks_diff(now, start))
        break
    if time.ticks_diff(now, start) > TIMEOUT_MS:
        db.stop(then="brake")
        raise RuntimeError("no red within %d ms" % TIMEOUT_MS)
    time.sleep_ms(10)
db.turn(180, then="brake")
print("facing back: heading %+.1f" % imu.heading())
