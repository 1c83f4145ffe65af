# SPDX-License-Identifier: MIT
"""Check one wheel before building the drive base: turn it by an angle, spin it at a speed, read it back.

Every motor driver has the same Motor methods, so this works for an ST-3032 wheel, an ST-3215 or a
JGB37-520 alike. Angles are degrees of the output shaft, speeds deg/s. angle() counts whole turns
too: after two turns it reads about 720.

Run with:
    openbricks run -n RobotA examples/motor_basics.py
    openbricks sim run examples/motor_basics.py
"""

import time

from openbricks.drivers.st3032 import ST3032Motor

wheel = ST3032Motor(servo_id=1, uart_id=1, tx=14, rx=41)
wheel.reset_angle(0)

wheel.run_angle(360, 720)  # two turns forward at 360 deg/s; blocks until done
print("after run_angle: %d deg" % wheel.angle())

wheel.run_speed(180)  # keep turning at 180 deg/s...
time.sleep_ms(1000)
print("turning at about %d deg/s" % wheel.speed())
wheel.brake()  # ...until told to stop
time.sleep_ms(300)
print("stopped at %d deg" % wheel.angle())
