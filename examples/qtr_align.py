# SPDX-License-Identifier: MIT
"""Square up on the edge of a line ahead with the QTRLineSensor bar.

Each half of the ten-element bar acts as one corner sensor, and each wheel servos on its own
half: it drives forward while its half sees mat, backs up once its half is on the line, and
settles where its half reads a mean ambient of 50, its elements straddling the near edge. The
half that arrives first holds while the other wheel brings its side up, so the bar, and the
chassis with it, ends square to the line whatever the approach angle.

Calibrate once with examples/qtr_calibrate.py first. The bar must be mounted ahead of the
wheels; the farther ahead, the finer the final heading.

Run with:
    openbricks run -n <hub> examples/qtr_align.py
    openbricks sim run examples/qtr_align.py --world zones
"""

import time

from openbricks.drivers.qtr import QTRLineSensor
from openbricks.drivers.st3032 import ST3032Motor
from openbricks.robotics import DriveBase

LEFT_ID, RIGHT_ID = 1, 2
UART_ID, TX, RX = 1, 14, 41
CALIBRATION_PATH = "/qtr.cal"

KP = 1.5  # wheel dps per point of ambient error (-50 .. +50)
EDGE_TOLERANCE = 6  # ambient points from 50 that count as on the edge
HALF = 5  # elements per side
SETTLED_SAMPLES = 20  # both halves on the edge this many samples in a row: done
POLL_MS = 5
TIMEOUT_MS = 15_000


def half_ambient(elements):
    return sum(e.ambient() for e in elements) / len(elements)


def wheel_dps(elements):
    """Forward over mat, backward over line, zero on the edge."""
    error = half_ambient(elements) - 50
    return 0 if abs(error) <= EDGE_TOLERANCE else KP * error


qtr = QTRLineSensor()
qtr.load_calibration(CALIBRATION_PATH)
left = ST3032Motor(servo_id=LEFT_ID, uart_id=UART_ID, tx=TX, rx=RX)
right = ST3032Motor(servo_id=RIGHT_ID, uart_id=UART_ID, tx=TX, rx=RX, invert=True)
db = DriveBase(left, right, wheel_diameter_mm=88, axle_track_mm=138)

print("aligning on the line ahead ...")
settled = 0
start = time.ticks_ms()
while settled < SETTLED_SAMPLES:
    if time.ticks_diff(time.ticks_ms(), start) > TIMEOUT_MS:
        db.stop(then="brake")
        raise RuntimeError("not square on a line within %d ms: is there a line ahead?" % TIMEOUT_MS)
    reading = qtr.read()
    speeds = (wheel_dps(reading.elements[:HALF]), wheel_dps(reading.elements[-HALF:]))
    settled = settled + 1 if speeds == (0, 0) else 0
    db.move_wheels(speeds[0], speeds[1])
    time.sleep_ms(POLL_MS)
db.stop(then="brake")
print("aligned: square on the edge after %d ms" % time.ticks_diff(time.ticks_ms(), start))
