# SPDX-License-Identifier: MIT
"""Calibrate the QTRLineSensor bar on your mat and save it for every later run.

Put the robot with the bar over a line. The robot turns in place a little to the left, past
centre to the right, and back, so every element sweeps over both line and mat while
calibrate() records each one's extremes; then the calibration is saved to the hub (with the
wiring it belongs to) and each element's span is printed. An element whose span is much
narrower than its neighbours' points at a mounting or wiring problem (manual 2.3.1: a pull-up
on GPIO 3 narrows element [2]).

Recalibrate after remounting the bar or changing mats.

Run with:
    openbricks run -n <hub> examples/qtr_calibrate.py
    openbricks sim run examples/qtr_calibrate.py --world line_track
"""

from openbricks.drivers.qtr import QTRLineSensor
from openbricks.drivers.st3032 import ST3032Motor

LEFT_ID, RIGHT_ID = 1, 2
UART_ID, TX, RX = 1, 14, 41
CALIBRATION_PATH = "/qtr.cal"
SWEEP_DPS = 120
SWEEP_MS = 450

qtr = QTRLineSensor()
left = ST3032Motor(servo_id=LEFT_ID, uart_id=UART_ID, tx=TX, rx=RX)
right = ST3032Motor(servo_id=RIGHT_ID, uart_id=UART_ID, tx=TX, rx=RX, invert=True)

print("sweeping the bar over the line ...")
for direction, duration in ((-1, SWEEP_MS), (1, 2 * SWEEP_MS), (-1, SWEEP_MS)):
    left.run_speed(direction * SWEEP_DPS)
    right.run_speed(-direction * SWEEP_DPS)
    qtr.calibrate(duration_ms=duration)
left.brake()
right.brake()

spans = [hi - lo for lo, hi in qtr.calibration()]
for i, span in enumerate(spans):
    print("element [%d] GPIO %d: span %d" % (i, qtr.pins[i], span))
qtr.save_calibration(CALIBRATION_PATH)
print("saved to %s" % CALIBRATION_PATH)
