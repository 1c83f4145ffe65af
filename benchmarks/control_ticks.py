"""Cost of one control tick of the drivebase and servo cores: in pure C, and through the host binding.

The C figures come from ``native/bench_ticks.c``, compiled here with ``gcc -O2`` against the cores in
``firmware/native`` (so they measure the sources as they are, not an installed build). The binding
figures time a plain Python loop around the ``update()`` fast paths, loop included, as a simulator
drives them; the full control period is one drivebase tick plus both wheels' servo ticks.
"""

from __future__ import annotations

import statistics
import time

from benchmarks import Row
from benchmarks._native_bench import run_c_benchmark

CORES = ("control", "drivebase", "trajectory", "observer", "servo")

BINDING_TICKS = 200_000
BINDING_ROUNDS = 5


def c_ticks() -> list[Row]:
    out = run_c_benchmark("bench_ticks.c", CORES)
    rows = []
    labels = {
        "drivebase_tick": "C: drivebase tick",
        "servo_tick": "C: servo tick",
        "control_period": "C: control period (drivebase + 2 servos)",
    }
    for line in out.splitlines():
        name, best, median = line.split()
        rows.append(Row(labels[name], float(best), "ns", f"best of 7; median {float(median):.1f} ns"))
    return rows


def wheel_angles(n: int) -> list[float]:
    """Encoder readings of a wheel cruising at 360 deg/s, quantised to 4096 counts per turn."""
    step = 360.0 / 4096.0
    return [int(i * 0.36 / step) * step for i in range(n)]


def time_loop(loop, rounds: int = BINDING_ROUNDS) -> tuple[float, float]:
    """Best and median ns per iteration of loop() over BINDING_TICKS iterations."""
    loop()  # warm-up
    per_tick = []
    for _ in range(rounds):
        start = time.perf_counter_ns()
        loop()
        per_tick.append((time.perf_counter_ns() - start) / BINDING_TICKS)
    return min(per_tick), statistics.median(per_tick)


def binding_ticks() -> list[Row]:
    import openbricks_native as native

    angles = wheel_angles(BINDING_TICKS)

    def fresh():
        db = native.DriveBase(56.0, 114.0)
        db.settings(straight_speed=360.0)
        db.drive(360.0 * 3.14159265 * 56.0 / 360.0, 0.0)  # a speed command never ends: every tick controls
        left, right = native.Servo(), native.Servo()
        left.run_speed(360.0)
        right.run_speed(360.0)
        return db, left, right

    def drivebase_loop():
        db, _, _ = fresh()
        update = db.update
        for now, angle in enumerate(angles):
            update(now, angle, angle)

    def servo_loop():
        _, servo, _ = fresh()
        update = servo.update
        for now, angle in enumerate(angles):
            update(now, angle)

    def period_loop():
        db, left, right = fresh()
        db_update, left_update, right_update = db.update, left.update, right.update
        for now, angle in enumerate(angles):
            db_update(now, angle, angle)
            left_update(now, angle)
            right_update(now, angle)

    def empty_loop():
        for _now, _angle in enumerate(angles):
            pass

    rows = []
    for label, loop in (
        ("binding: DriveBase.update", drivebase_loop),
        ("binding: Servo.update", servo_loop),
        ("binding: control period (DriveBase + 2 Servos)", period_loop),
        ("binding: the bare Python loop, for scale", empty_loop),
    ):
        best, median = time_loop(loop)
        rows.append(
            Row(label, best, "ns", f"best of {BINDING_ROUNDS}; median {median:.1f} ns; loop included")
        )
    return rows


# The same period through the reference's C extension (openbricks_sim._native of 4.36.0): its
# DriveBase tick writes each servo's target speed, then each Servo tick turns an encoder count into
# power. Same tick count, rounds, encoder ramp and loop shape as ours.
REFERENCE_PERIOD = """
import statistics, time
import openbricks_sim._native as n
TICKS, ROUNDS = {ticks}, {rounds}
counts = [int(i * 0.36 / (360.0 / 4096.0)) for i in range(TICKS)]
def loop():
    left, right = n.Servo(4096), n.Servo(4096)
    db = n.DriveBase(left, right, 56.0, 114.0)
    db.straight(0, 100000.0, 175.9)
    db_tick, left_tick, right_tick = db.tick, left.tick, right.tick
    for now, count in enumerate(counts):
        db_tick(now)
        left_tick(count, now)
        right_tick(count, now)
loop()
per_tick = []
for _ in range(ROUNDS):
    start = time.perf_counter_ns()
    loop()
    per_tick.append((time.perf_counter_ns() - start) / TICKS)
print(min(per_tick), statistics.median(per_tick))
"""


def reference_period(ours_ns: float) -> list[Row]:
    from benchmarks import _reference as reference

    out = reference.run_python(REFERENCE_PERIOD.format(ticks=BINDING_TICKS, rounds=BINDING_ROUNDS))
    best, median = (float(v) for v in out.split())
    return [
        Row(
            "reference 4.36.0: control period (DriveBase + 2 Servos)",
            best,
            "ns",
            f"best of {BINDING_ROUNDS}; median {median:.1f} ns; loop included",
        ),
        Row("control period, ours / reference", ours_ns / best, "x", "best vs best; below 1 is faster"),
    ]


def run() -> list[Row]:
    binding = binding_ticks()
    period = next(row.value for row in binding if row.case.startswith("binding: control period"))
    return c_ticks() + binding + reference_period(period)
