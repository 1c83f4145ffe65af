"""A DriveBase over two ST-3032s kept under control by the hard tick while Python is busy.

    build/micropython/micropython tests/micropython/hard_tick_drive.py    # from the repository root

Runs on the unix MicroPython with the real `_openbricks_native` and `_openbricks_bench` (emulated
ST-3032s on an in-memory wire, in C): the runtime's own drivers and DriveBase adopt the servos onto
the C bus engine, and from then on the 1 kHz hard tick (a host thread here, esp_timer on the hub)
runs the drive base's controller and the engine with no Python call. The program then spins in
Python loops that never sleep and never call the runtime; the robot must still drive its moves.
Prints one `@result {json}` line with what it measured (test_hard_tick_on_unix_micropython.py).
"""

import json
import sys

sys.path[:0] = [""]

import _openbricks_bench  # noqa: E402

from tests.micropython.hard_tick_hub import busy, install_machine  # noqa: E402

bench = _openbricks_bench.BenchBus((1, 2))


install_machine(bench)

import _openbricks_native  # noqa: E402

from openbricks.drivers.st3032 import ST3032Motor  # noqa: E402
from openbricks.robotics import DriveBase  # noqa: E402

WHEEL_MM = 56.0
TRACK_MM = 120.0


def wheel_mm(servo_id, start_deg):
    return (bench.angle_deg(servo_id) - start_deg) * 3.141592653589793 * WHEEL_MM / 360


def main():
    left = ST3032Motor(servo_id=1, uart_id=1, tx=17, rx=18)
    right = ST3032Motor(servo_id=2, uart_id=1, tx=17, rx=18, invert=True)
    db = DriveBase(left, right, wheel_diameter_mm=WHEEL_MM, axle_track_mm=TRACK_MM)
    process = _openbricks_native.motor_process
    engine = db._pair.wheels[0][0].engine
    start = (bench.angle_deg(1), bench.angle_deg(2))
    ticks0, hard0, bus0 = process.tick_count, process.hard_tick_count(), engine.bus_stats()["ticks"]
    db.straight(300, wait=False)
    rounds = busy(4500)
    ticks1, hard1, bus1 = process.tick_count, process.hard_tick_count(), engine.bus_stats()["ticks"]
    straight = {
        "done": db.done(),
        "left_mm": wheel_mm(1, start[0]),
        "right_mm": -wheel_mm(2, start[1]),
        "distance_mm": db.distance(),
        "busy_rounds": rounds,
        "control_ticks": ticks1 - ticks0,
        "hard_ticks": hard1 - hard0,
        "bus_ticks": bus1 - bus0,
    }
    mid = (bench.angle_deg(1), bench.angle_deg(2))
    db.turn(90, wait=False)
    busy(4000)
    turn = {
        "done": db.done(),
        "left_mm": wheel_mm(1, mid[0]),
        "right_mm": -wheel_mm(2, mid[1]),
        "angle_deg": db.angle(),
    }
    ticks, expected = process.hard_tick_selftest(duration_ms=200)
    db.stop()
    print("@result " + json.dumps({"straight": straight, "turn": turn, "selftest": [ticks, expected]}))


main()
