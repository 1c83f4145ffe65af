"""A DriveBase over two JGB37-520s kept under control by the hard tick while Python is busy.

    build/micropython/micropython tests/micropython/hard_tick_dc_drive.py    # from the repository root

Runs on the unix MicroPython with the real `_openbricks_native` and `_openbricks_bench`: each wheel
is an emulated DC gear motor with its encoder, in C (`BenchDCMotor`), standing where the hub's
H-bridge channel and PCNT unit are. The runtime's own JGB37Motor builds its bridge on the firmware's
H-bridge core and its encoder on the PCNT encoder core, exactly as on the hub but with the emulated
motor's terminals and encoder in place of GPIO/LEDC and the PCNT peripheral; its motor IO is then
joined in C, so the DriveBase's controller runs in the 1 kHz hard tick (a host thread here,
esp_timer on the hub) with no Python call. The program then spins in Python loops that never sleep
and never call the runtime; the robot must still drive its moves.
Prints one `@result {json}` line with what it measured (test_hard_tick_dc_on_unix_micropython.py).
"""

import json
import sys

sys.path[:0] = [""]

import _openbricks_bench  # noqa: E402

from tests.micropython.hard_tick_hub import busy, install_machine  # noqa: E402

install_machine(None)  # no serial bus on this robot: the bridges and encoders are the firmware's


class _IdleTimer:
    """machine.Timer whose callback never fires. A DriveBase asks for a fallback tick when it is built,
    before its controller is subscribed (the hub answers that it ticks itself; this port only does once
    everything subscribed is native). Nothing of the drive may come from such a timer here: every
    control tick the test counts has to be the hard tick's."""

    PERIODIC = 1

    def __init__(self, timer_id):
        self.timer_id = timer_id

    def init(self, **_settings):
        pass

    def deinit(self):
        pass


sys.modules["machine"].Timer = _IdleTimer

import _openbricks_native  # noqa: E402

from openbricks.drivers import encoder, l298n  # noqa: E402
from openbricks.drivers.jgb37_520 import JGB37Motor  # noqa: E402
from openbricks.robotics import DriveBase  # noqa: E402

WHEEL_MM = 65.0
TRACK_MM = 150.0
JGB37_CPR = 1320

# The manual's DC wiring: left IN1/IN2/EN on GPIO 1/2/17, right on 9/10/11; encoders on 4/5 and 6/7.
LEFT, RIGHT = _openbricks_bench.BenchDCMotor(), _openbricks_bench.BenchDCMotor()
BY_PWM_PIN = {17: LEFT, 11: RIGHT}
BY_ENCODER_PIN = {4: LEFT, 6: RIGHT}


def hub_bridge(in1, in2, pwm, invert=False, freq_hz=1000):
    """The firmware's HBridge constructor, driving the emulated motor instead of GPIO and LEDC."""
    return _openbricks_native.HBridge(invert=invert, freq_hz=freq_hz, outputs=BY_PWM_PIN[pwm].pins())


def hub_counter(counts_per_rev, invert=False, pin_a=None, pin_b=None, unit=0, filter=1023):
    """The firmware's PCNTEncoder constructor, counting the emulated encoder instead of a PCNT unit."""
    return _openbricks_native.PCNTEncoder(
        counts_per_rev, invert=invert, counter=BY_ENCODER_PIN[pin_a].counter()
    )


l298n._hub_bridge = lambda: hub_bridge
encoder._hub_counter = lambda: hub_counter


def wheel_mm(motor, start_deg, sign=1):
    return sign * (motor.angle_deg() - start_deg) * 3.141592653589793 * WHEEL_MM / 360


def main():
    left = JGB37Motor(in1=1, in2=2, pwm=17, encoder_a=4, encoder_b=5)
    right = JGB37Motor(in1=9, in2=10, pwm=11, encoder_a=6, encoder_b=7, invert=True)
    db = DriveBase(left, right, wheel_diameter_mm=WHEEL_MM, axle_track_mm=TRACK_MM)
    process = _openbricks_native.motor_process
    start = (LEFT.angle_deg(), RIGHT.angle_deg())
    ticks0, hard0 = process.tick_count, process.hard_tick_count()
    writes0, reads0 = LEFT.writes() + RIGHT.writes(), LEFT.reads() + RIGHT.reads()
    db.straight(300, wait=False)
    rounds = busy(4500)
    straight = {
        "done": db.done(),
        "left_mm": wheel_mm(LEFT, start[0]),
        "right_mm": wheel_mm(RIGHT, start[1], -1),  # mounted mirror-image: forward turns it backwards
        "distance_mm": db.distance(),
        "busy_rounds": rounds,
        "ticks_itself": _openbricks_native.ticks_itself(),
        "control_ticks": process.tick_count - ticks0,
        "hard_ticks": process.hard_tick_count() - hard0,
        "bridge_writes": LEFT.writes() + RIGHT.writes() - writes0,
        "encoder_reads": LEFT.reads() + RIGHT.reads() - reads0,
        "levels": [list(LEFT.levels()), list(RIGHT.levels())],
    }
    mid = (LEFT.angle_deg(), RIGHT.angle_deg())
    db.turn(90, wait=False)
    busy(4000)
    turn = {
        "done": db.done(),
        "left_mm": wheel_mm(LEFT, mid[0]),
        "right_mm": wheel_mm(RIGHT, mid[1], -1),
        "angle_deg": db.angle(),
    }
    db.stop()
    left.dc(40)  # a direct command takes the wheel back from the drive base, through the same bridge
    busy(300)
    direct = {"speed_dps": LEFT.speed_dps(), "levels": list(LEFT.levels())}
    left.coast()
    print("@result " + json.dumps({"straight": straight, "turn": turn, "direct": direct}))


main()
