"""Sensors the hard tick reads while Python is busy: a PCNT encoder and a gyro drive base.

    build/micropython/micropython tests/micropython/hard_tick_sensors.py    # from the repository root

Runs on the unix MicroPython with the real `_openbricks_native` and `_openbricks_bench` (emulated
hardware in C on native links, as the hub's peripherals are):

- an MG370 shaft turning at 22000 counts/s behind a PCNT unit whose 16-bit counter returns to 0
  every 32767 counts: `PCNTEncoder` on it is read by the hard tick every millisecond, so a program
  that spins for three seconds without reading it (two wraps) still gets the exact count. (The
  rate leaves a loaded host's timer thread 740 ms of stall before a step between two reads gets
  ambiguous; the hub's esp_timer does not stall.)
- an ICM-45686 riding on a robot of two emulated ST-3032s whose tyres scrub (the body turns 0.9 of
  what the wheels say): the runtime's ICM45686 driver on the firmware's C driver, sampled by the hard
  tick, and a DriveBase with use_gyro(True) reading that heading in C, so the drive base stays on
  the hard tick and its turn lands on the true heading while Python spins.

Prints one `@result {json}` line with what it measured (test_hard_tick_sensors_on_unix_micropython.py).
"""

import json
import sys

sys.path[:0] = [""]

import _openbricks_bench  # noqa: E402

from tests.micropython.hard_tick_hub import busy, install_machine  # noqa: E402

bench = _openbricks_bench.BenchBus((1, 2))


install_machine(bench)

import _openbricks_native  # noqa: E402

from openbricks.drivers import icm45686  # noqa: E402
from openbricks.drivers.st3032 import ST3032Motor  # noqa: E402
from openbricks.robotics import DriveBase  # noqa: E402

WHEEL_MM = 56.0
TRACK_MM = 120.0
SCRUB = 0.9  # the body turns this share of what the wheels say
MG370_CPR = 68028


def encoder():
    shaft = _openbricks_bench.BenchEncoder(0)
    enc = _openbricks_native.PCNTEncoder(MG370_CPR, counter=shaft)
    start = shaft.true_count()
    reads0 = shaft.reads()
    shaft.set_rate(22_000)
    rounds = busy(3000)
    shaft.set_rate(0)
    result = {
        "busy_rounds": rounds,
        "count": enc.count(),
        "true_count": shaft.true_count() - start,
        "turns": enc.angle() / 360,
        "hard_reads": shaft.reads() - reads0,
    }
    enc.close()
    reads = shaft.reads()
    busy(50)
    result["reads_after_close"] = shaft.reads() - reads
    return result


def gyro_drive():
    link = _openbricks_bench.BenchIMU(bench, 1, 2, wheel_mm=WHEEL_MM, track_mm=TRACK_MM, true_scale=SCRUB)
    # The firmware's ICM45686 constructor, on the emulated chip instead of the ESP32's SPI.
    icm45686._hub_chip = lambda: lambda scale, **_wiring: _openbricks_native.ICM45686(link, scale=scale)
    imu = icm45686.ICM45686(sck=4, mosi=5, miso=6, cs=15)
    left = ST3032Motor(servo_id=1, uart_id=1, tx=17, rx=18)
    right = ST3032Motor(servo_id=2, uart_id=1, tx=17, rx=18, invert=True)
    db = DriveBase(left, right, wheel_diameter_mm=WHEEL_MM, axle_track_mm=TRACK_MM, imu=imu)
    busy(700)  # at rest while the hard tick samples: the gyro bias locks
    calibrated = imu.calibrated()
    db.use_gyro(True)
    process = _openbricks_native.motor_process
    ticks0, hard0, bursts0 = process.tick_count, process.hard_tick_count(), link.bursts()
    heading0, unseen0 = link.true_heading(), link.unseen_deg()
    db.turn(90, wait=False)
    rounds = busy(4000)
    result = {
        "calibrated": calibrated,
        "busy_rounds": rounds,
        "done": db.done(),
        "angle_deg": db.angle(),
        "true_turn_deg": link.true_heading() - heading0,
        "unseen_deg": link.unseen_deg() - unseen0,
        "imu_heading_deg": imu.heading(),
        "ticks_itself": _openbricks_native.ticks_itself(),
        "control_ticks": process.tick_count - ticks0,
        "hard_ticks": process.hard_tick_count() - hard0,
        "imu_bursts": link.bursts() - bursts0,
        "imu_stats": list(imu.stats()),
        "imu_max_gap_us": link.max_gap_us(),
    }
    db.stop()
    return result


print("@result " + json.dumps({"encoder": encoder(), "gyro": gyro_drive()}))
