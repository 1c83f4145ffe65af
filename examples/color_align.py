# SPDX-License-Identifier: MIT
"""Square the robot up on a dark line with two colour sensors, one at each front corner.

Two phases. Seek: drive slowly toward the line; the moment a sensor crosses onto it, its wheel
stops while the other keeps rolling, pivoting the chassis until the second sensor reaches the
line too. Settle: a wheel never stops dead at the instant its sensor fires (it coasts down its
ramp, and its stopping carries the other sensor forward), so each wheel then servos on its own
sensor, forward over mat and back over line, until both sensors straddle the line's near edge.
Both on the edge means the sensor pair, and so the chassis, lies square to the line however
crooked the approach was. The sensors must sit ahead of the axle, mounted symmetrically; the
farther apart, the finer the final heading.

A black line on a light mat is simply too dark to be mat: ambient() below LINE_AMBIENT. The
edge is taken halfway between the mat's ambient (read at the start) and black. Print ambient()
over your own mat and line and set LINE_AMBIENT between the two.

Wiring: TCA9548A on I2C0 (SDA 15, SCL 16), a TCS34725 on channel 0 (left) and channel 1 (right).

Run with:
    openbricks run -n <hub> examples/color_align.py
    openbricks sim run examples/color_align.py --world zones
"""

from machine import I2C, Pin

from openbricks.drivers.st3032 import ST3032Motor
from openbricks.drivers.tca9548a import TCA9548A
from openbricks.drivers.tcs34725 import TCS34725
from openbricks.robotics import DriveBase
from openbricks.tools import wait

LEFT_ID, RIGHT_ID = 1, 2
UART_ID, TX, RX = 1, 14, 41
LINE_AMBIENT = 20
APPROACH_DPS = 100
KP = 2.0  # wheel dps per ambient point off the edge value
EDGE_TOLERANCE = 4  # ambient points from the edge value that count as on it
SETTLED_SAMPLES = 20  # both sensors on the edge this many samples in a row: done
POLL_MS = 5
TIMEOUT_MS = 10_000

left_motor = ST3032Motor(servo_id=LEFT_ID, uart_id=UART_ID, tx=TX, rx=RX)
right_motor = ST3032Motor(servo_id=RIGHT_ID, uart_id=UART_ID, tx=TX, rx=RX, invert=True)
db = DriveBase(left_motor, right_motor, wheel_diameter_mm=88, axle_track_mm=138)

mux = TCA9548A(I2C(0, sda=Pin(15), scl=Pin(16), freq=400_000))
sensors = (TCS34725(mux[0]), TCS34725(mux[1]))  # left, right


def seek_line():
    """Drive up to the line; each wheel stops when its sensor sees it."""
    speeds = [APPROACH_DPS, APPROACH_DPS]
    last = [None, None]
    db.move_wheels(*speeds)
    for _ in range(TIMEOUT_MS // POLL_MS):
        for side in (0, 1):
            if speeds[side] == 0:
                continue
            last[side] = sensors[side].ambient()
            if last[side] < LINE_AMBIENT:
                speeds[side] = 0
                db.move_wheels(*speeds)
                print("%s sensor on the line (ambient %d)" % (("left", "right")[side], last[side]))
        if speeds == [0, 0]:
            return
        wait(POLL_MS)
    raise RuntimeError(
        "no line within %d ms (last ambient: left=%r right=%r): is the line in reach, and is "
        "LINE_AMBIENT set for this mat?" % (TIMEOUT_MS, last[0], last[1])
    )


def settle_on_edge(edge_ambient):
    """Servo each wheel on its own sensor until both read the edge value."""
    settled = 0
    for _ in range(TIMEOUT_MS // POLL_MS):
        speeds = []
        for sensor in sensors:
            error = sensor.ambient() - edge_ambient
            speeds.append(0 if abs(error) <= EDGE_TOLERANCE else KP * error)
        settled = settled + 1 if speeds == [0, 0] else 0
        if settled >= SETTLED_SAMPLES:
            return
        db.move_wheels(*speeds)
        wait(POLL_MS)
    raise RuntimeError("the sensors did not settle on the line's edge within %d ms" % TIMEOUT_MS)


mat_ambient = min(sensor.ambient() for sensor in sensors)
print("aligning on the line ahead (mat ambient %d) ..." % mat_ambient)
try:
    seek_line()
    settle_on_edge(mat_ambient // 2)
finally:
    db.stop(then="brake")
print("aligned: square to the line")
