# SPDX-License-Identifier: MIT
"""Live graphs in the console: plot() the robot's distance and speed while it drives.

In the console, every plot(name, value) becomes a point on the Telemetry page's graph of `name` and
is kept with the run in the history. Run without the console, the same call prints
"plot: name = value", so the program works everywhere unchanged.

Run with:
    openbricks run -n RobotA examples/telemetry_plot.py   (the console watching: live graphs)
    openbricks sim run examples/telemetry_plot.py
"""

import time

from openbricks.drivers.st3032 import ST3032Motor
from openbricks.robotics import DriveBase
from openbricks.tools import StopWatch, plot

left = ST3032Motor(servo_id=1, uart_id=1, tx=14, rx=41)
right = ST3032Motor(servo_id=2, uart_id=1, tx=14, rx=41, invert=True)
db = DriveBase(left, right, wheel_diameter_mm=88, axle_track_mm=138)

watch = StopWatch()
db.straight(600, wait=False)
while not db.done():
    plot("distance_mm", db.distance())
    plot("left_dps", left.speed())
    time.sleep_ms(100)
print("600 mm in %d ms" % watch.time())
