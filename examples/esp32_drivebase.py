# SPDX-License-Identifier: MIT
"""The DC gear-motor build (manual 2.7): two JGB37-520 motors with Hall encoders behind an L298N,
driving a square while an ICM-45686 reports the heading it measured after every turn.

GPIO map of the ESP32-S3 build, as the manual's table gives it:

    left motor   IN1/IN2 1, 2   PWM (ENA) 17   encoder A/B 7, 8
    right motor  IN3/IN4 9, 10  PWM (ENB) 11   encoder A/B 12, 13

The motors take GPIO 11, 12, 13 and 17, which the serial-bus build gives the IMU's SPI bus, so
here the ICM-45686 sits on SCK 4, MOSI 5, MISO 6, CS 21 (the simulated DC robot is wired the same
way). Buttons (38, 39), I2C (15/16) and the serial-bus UART (14/41) stay free.

Each encoder is counted by a PCNT unit of the ESP32 (machine.Encoder), so the closed loop costs the
CPU nothing per encoder edge. The right motor is mounted mirrored: invert=True.

Run with:
    openbricks run -n <hub> examples/esp32_drivebase.py
    openbricks sim run examples/esp32_drivebase.py
"""

import time

from openbricks.drivers.icm45686 import ICM45686
from openbricks.drivers.jgb37_520 import JGB37Motor
from openbricks.robotics import DriveBase

LEFT_IN1, LEFT_IN2, LEFT_PWM = 1, 2, 17
LEFT_ENCODER_A, LEFT_ENCODER_B = 7, 8
RIGHT_IN1, RIGHT_IN2, RIGHT_PWM = 9, 10, 11
RIGHT_ENCODER_A, RIGHT_ENCODER_B = 12, 13
SCK, MOSI, MISO, CS = 4, 5, 6, 21

WHEEL_DIAMETER_MM = 65
AXLE_TRACK_MM = 120
SIDE_MM = 300

imu = ICM45686(sck=SCK, mosi=MOSI, miso=MISO, cs=CS)
while not imu.calibrated():  # keep still while the gyro learns its bias
    time.sleep_ms(50)
imu.reset_heading(0)

left = JGB37Motor(
    in1=LEFT_IN1, in2=LEFT_IN2, pwm=LEFT_PWM, encoder_a=LEFT_ENCODER_A, encoder_b=LEFT_ENCODER_B
)
right = JGB37Motor(
    in1=RIGHT_IN1,
    in2=RIGHT_IN2,
    pwm=RIGHT_PWM,
    encoder_a=RIGHT_ENCODER_A,
    encoder_b=RIGHT_ENCODER_B,
    invert=True,
)
db = DriveBase(left, right, wheel_diameter_mm=WHEEL_DIAMETER_MM, axle_track_mm=AXLE_TRACK_MM)

print("square: %d mm sides on the encoders" % SIDE_MM)
for side in range(4):
    db.straight(SIDE_MM)
    db.turn(90)
    print("side %d: odometry %+.1f deg, gyro %+.1f deg" % (side + 1, db.angle(), imu.heading()))
db.stop(then="brake")
print("done: %.0f mm driven" % db.distance())
