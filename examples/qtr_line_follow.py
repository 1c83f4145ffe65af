# SPDX-License-Identifier: MIT
"""Follow a black line's left edge with the QTRLineSensor bar, and stop at the finish bar.

The bar holds the line's LEFT edge under its channel-4 element ("left" mode),
so a branch leaving to the right never pulls the robot off the main line: it
only darkens the right half of the window. The whole window going dark for a
few samples in a row is the finish bar across the line.

Calibration: the robot sweeps the bar over the line itself before it starts,
turning a little left and right in place while calibrate() runs, so the
calibration always matches the mat under it. Start with the bar over the
line, the robot facing along it.

Every 5 ms the drive base's move_wheels() sets both wheel speeds at once (one
sync packet on the serial bus): a cruise speed plus and minus a
proportional-derivative correction of the edge error.

Run with:
    openbricks run -n <hub> examples/qtr_line_follow.py
    openbricks sim run examples/qtr_line_follow.py --world line_track
"""

import time

from openbricks.drivers.qtr import QTRLineSensor
from openbricks.drivers.st3032 import ST3032Motor
from openbricks.robotics import DriveBase

LEFT_ID, RIGHT_ID = 1, 2
UART_ID, TX, RX = 1, 14, 41

CRUISE_DPS = 300  # wheel speed on the straights (about 230 mm/s on 88 mm wheels)
KP = 4.0  # wheel dps per unit of edge error (-50 .. +50)
KD = 12.0  # wheel dps per unit of error change per sample
POLL_MS = 5
FINISH_SAMPLES = 4  # this many all-dark samples in a row = the finish bar
SWEEP_DPS = 120
SWEEP_MS = 450
TIMEOUT_MS = 60_000


def sweep_calibrate(qtr, db):
    """Turn left, right past centre, and back, calibrating all the way: every element sees line and mat."""
    for direction, duration in ((-1, SWEEP_MS), (1, 2 * SWEEP_MS), (-1, SWEEP_MS)):
        db.move_wheels(direction * SWEEP_DPS, -direction * SWEEP_DPS)
        qtr.calibrate(duration_ms=duration, poll_ms=POLL_MS)
    db.stop(then="brake")
    if not qtr.calibrated():
        raise RuntimeError(
            "the calibration sweep did not cross the line with every element (spans: %r); start with "
            "the bar over the line" % (qtr.calibration(),)
        )


def follow(qtr, db):
    qtr.set_mode("left")
    previous = 0
    dark_run = 0
    start = time.ticks_ms()
    while time.ticks_diff(time.ticks_ms(), start) < TIMEOUT_MS:
        reading = qtr.read()
        if reading.all_dark():
            dark_run += 1
            if dark_run >= FINISH_SAMPLES:
                return time.ticks_diff(time.ticks_ms(), start)
        else:
            dark_run = 0
        error = reading.edge_error()
        turn = KP * error + KD * (error - previous)
        previous = error
        db.move_wheels(CRUISE_DPS + turn, CRUISE_DPS - turn)
        time.sleep_ms(POLL_MS)
    raise RuntimeError("no finish bar within %d ms: is the robot still on the line?" % TIMEOUT_MS)


def main():
    qtr = QTRLineSensor()
    left = ST3032Motor(servo_id=LEFT_ID, uart_id=UART_ID, tx=TX, rx=RX)
    right = ST3032Motor(servo_id=RIGHT_ID, uart_id=UART_ID, tx=TX, rx=RX, invert=True)
    db = DriveBase(left, right, wheel_diameter_mm=88, axle_track_mm=138)
    print("calibrating: sweeping the bar over the line ...")
    sweep_calibrate(qtr, db)
    print("following the left edge ...")
    try:
        elapsed = follow(qtr, db)
    finally:
        db.stop(then="brake")
    print("finish bar reached after %.1f s" % (elapsed / 1000))


main()
