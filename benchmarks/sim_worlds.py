"""Simulator worlds: how fast the competition table steps, what the sensor models cost per read, and
how much memory a process holding the table needs.

The table is stepped the way a run steps it: the robot's wheels on native
servos ticked inside the physics step (no Python per step), in chunks of
10 ms as a program's sleeps would split it. Cases:

- open mat: the robot drives on the table, every block asleep (the common case);
- mission: the robot pushes one block 350 mm north toward its target row, then
  backs off and the block settles back to sleep;
- plough (stress): the robot shoves a whole row of six blocks into a pile, with
  up to six awake blocks in contact at once.

The empty world with the same robot is the baseline. Each case is run three
times and the best wall-clock figure kept, since other processes share the
CPU. Targets: the table >= 30x real time; <= 120 MB peak per process.
"""

from __future__ import annotations

import subprocess
import sys
import time

import openbricks_native as native
from benchmarks import Row
from openbricks_sim.physics import Physics
from openbricks_sim.sensors.color import TCS34725Model
from openbricks_sim.sensors.distance import ForwardRay
from openbricks_sim.sensors.mat import GroundProbe
from openbricks_sim.sensors.qtr import QTRBarModel
from openbricks_sim.worlds import wro

CHUNK_MS = 10
REPEATS = 3


def _real_time_factor(world: str, start_mm_deg, legs) -> float:
    """Best-of-REPEATS real-time factor of driving `legs` [(wheel_dps, ms), ...] from start_mm_deg."""
    best = 0.0
    for _ in range(REPEATS):
        physics = Physics(world, "st3032", seed=0, start_mm_deg=start_mm_deg)
        native.motor_process.reset()
        try:
            physics.attach_control()
            servos = [native.Servo(io=physics.wheel_io(wheel)) for wheel in (0, 1)]
            for servo in servos:
                native.motor_process.subscribe(servo)
            total_ms = 0
            start = time.perf_counter()
            for wheel_dps, ms in legs:
                for servo in servos:
                    servo.run_speed(wheel_dps)
                for _ in range(ms // CHUNK_MS):
                    physics.step(CHUNK_MS)
                total_ms += ms
            best = max(best, total_ms / 1000 / (time.perf_counter() - start))
        finally:
            native.motor_process.reset()
            physics.close()
    return best


def _per_call_us(fn, n=2000) -> float:
    fn()
    start = time.perf_counter()
    for _ in range(n):
        fn()
    return (time.perf_counter() - start) / n * 1e6


def _sensor_costs() -> list[Row]:
    physics = Physics("wro", "st3032", seed=0)
    try:
        probe = GroundProbe(physics.model, physics.data)
        clock = {"us": 0}

        def now_us():
            return clock["us"]

        qtr = QTRBarModel(probe, now_us)
        colour = TCS34725Model(probe, "color_0", now_us)
        ray = ForwardRay(physics.model, physics.data)

        def qtr_read():
            clock["us"] += 1  # a new instant: all ten channels sampled afresh
            qtr.raw12()

        return [
            Row("QTR bar sample (10 channels, one instant)", _per_call_us(qtr_read), "us"),
            Row("colour sensor sample (TCS34725 footprint)", _per_call_us(colour.light_per_cycle), "us"),
            Row("laser range ray cast", _per_call_us(ray.range_mm), "us"),
        ]
    finally:
        physics.close()


# VmHWM, not getrusage's ru_maxrss: Linux carries ru_maxrss across exec, so a child started from
# this (by then large) benchmark process would report the parent's peak instead of its own.
_RSS_PROBE = """
from openbricks_sim.simulation import Simulation
sim = Simulation("wro", "st3032", seed=0)
sim.physics.step(1000)
sim.close()
with open("/proc/self/status") as status:
    peak_kb = next(int(line.split()[1]) for line in status if line.startswith("VmHWM:"))
print(peak_kb / 1024)
"""


def _peak_rss_mb() -> float:
    out = subprocess.run([sys.executable, "-c", _RSS_PROBE], capture_output=True, text=True, check=True)
    return float(out.stdout.strip().splitlines()[-1])


def run() -> list[Row]:
    _, row_x, row_y, _ = wro.layout(0)[0]  # the west end of the north row of blocks
    _, block_x, _, _ = wro.layout(0)[2]
    drive = [(300.0, 4000)]
    rows = [
        Row(
            "empty world, robot driving",
            _real_time_factor("empty", (0.0, 0.0, 0.0), drive),
            "x real time",
            "baseline",
        ),
        Row(
            "WRO table, 12 blocks asleep, robot driving",
            _real_time_factor("wro", (-1011.0, 0.0, 0.0), drive),
            "x real time",
            "target >= 30",
        ),
        Row(
            "WRO table, mission: push one block, back off",
            _real_time_factor("wro", (block_x, 0.0, -90.0), [(300.0, 2000), (-300.0, 1500), (0.0, 1500)]),
            "x real time",
            "target >= 30",
        ),
        Row(
            "WRO table, stress: plough a row of six blocks",
            _real_time_factor("wro", (row_x - 140.0, row_y, 0.0), drive),
            "x real time",
            "informational",
        ),
    ]
    rows.extend(_sensor_costs())
    rows.append(Row("peak RSS, process simulating the WRO table", _peak_rss_mb(), "MB", "bar <= 120"))
    return rows


if __name__ == "__main__":
    for row in run():
        print(f"{row.case:48s} {row.value:10.1f} {row.unit} {row.note}")
