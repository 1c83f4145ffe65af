# SPDX-License-Identifier: MIT
"""Name the colour under each of two colour sensors while the robot drives across a mat.

Each TCS34725 gives a brightness (ambient(), 0..100) and a brightness-free colour (rgb(),
scaled by the clear channel so that white reads about 255, 255, 255 in any light). Together they
tell black (too dark to be anything else), white (bright and balanced) and the print colours
(one or two channels well above the rest) apart. The robot drives straight for DISTANCE_MM and
prints each sensor's colour every time it changes.

Wiring: TCA9548A on I2C0 (SDA 15, SCL 16), a TCS34725 on channel 0 (left) and channel 1 (right).

Run with:
    openbricks run -n <hub> examples/color_array.py
    openbricks sim run examples/color_array.py --world zones
"""

import time

from machine import I2C, Pin

from openbricks.drivers.st3032 import ST3032Motor
from openbricks.drivers.tca9548a import TCA9548A
from openbricks.drivers.tcs34725 import TCS34725
from openbricks.robotics import DriveBase

LEFT_ID, RIGHT_ID = 1, 2
UART_ID, TX, RX = 1, 14, 41
DISTANCE_MM = 900
SPEED = 150  # wheel-deg/s: slow enough that each band is seen several times
POLL_MS = 10
BLACK_AMBIENT = 20
WHITE_SPREAD = 0.3  # channels within 30 % of each other: no colour to name
HUES = (("red", 25), ("yellow", 80), ("green", 170), ("blue", 290))  # upper hue bound of each name


def colour_name(sensor):
    """Black by brightness; white by a small spread between channels; else the hue's name.

    Hue (0 red, 60 yellow, 120 green, 240 blue) rather than per-channel thresholds keeps a sensor
    half over a zone's edge, which sees the colour washed out with white, naming the colour.
    """
    if sensor.ambient() < BLACK_AMBIENT:
        return "black"
    r, g, b = sensor.rgb()
    hi, lo = max(r, g, b), min(r, g, b)
    if hi == 0 or hi - lo < WHITE_SPREAD * hi:
        return "white"
    if hi == r:
        hue = (60 * (g - b) / (hi - lo)) % 360
    elif hi == g:
        hue = 60 * (b - r) / (hi - lo) + 120
    else:
        hue = 60 * (r - g) / (hi - lo) + 240
    for name, below in HUES:
        if hue < below:
            return name
    return "red"


mux = TCA9548A(I2C(0, sda=Pin(15), scl=Pin(16), freq=400_000))
sensors = (("left", TCS34725(mux[0])), ("right", TCS34725(mux[1])))
left = ST3032Motor(servo_id=LEFT_ID, uart_id=UART_ID, tx=TX, rx=RX)
right = ST3032Motor(servo_id=RIGHT_ID, uart_id=UART_ID, tx=TX, rx=RX, invert=True)
db = DriveBase(left, right, wheel_diameter_mm=88, axle_track_mm=138)
db.settings(straight_speed=SPEED)

seen = {}
db.straight(DISTANCE_MM, then="brake", wait=False)
while True:
    for side, sensor in sensors:
        name = colour_name(sensor)
        if seen.get(side) != name:
            seen[side] = name
            print("%s: %s" % (side, name))
    if db.done():
        break
    time.sleep_ms(POLL_MS)
print("done")
