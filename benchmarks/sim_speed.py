"""Where the simulator's time goes: bare MuJoCo steps against our controlled steps on the same model,
and the real-time factor of a whole program run.

- bare: `mujoco.mj_step(nstep=N)` on the st3032 chassis in the empty world, no control callback.
- controlled: the same model with the native control path on: every step ticks the hub's
  motor_process (a DriveBase on the adopted serial-bus wheels, as a DriveBase program runs) and
  the world's device firmware, then applies both motor models, all inside one mj_step(nstep=N).
- overhead: controlled over bare, the product's "shim + control <= 30 %" figure.
- program: a hub program driving with the unchanged ST3032Motor driver through the emulated bus
  (a register transaction every 20 ms, as a polling loop would), run by openbricks_sim.run.

Bare and controlled are measured in alternating rounds and the best of each is kept, so a busy
machine slows both alike instead of skewing the ratio.
"""

from __future__ import annotations

import statistics
import time

from benchmarks import Row

STEPS = 5000
ROUNDS = 7

PROGRAM = """\
import time
from openbricks.drivers.st3032 import ST3032Motor

left = ST3032Motor(1)
right = ST3032Motor(2, invert=True)
for speed in (300, -300, 500, 200):
    left.run_speed(speed)
    right.run_speed(speed)
    for _ in range(100):
        time.sleep_ms(20)
        left.angle()
left.brake()
right.brake()
"""


def _per_step_us(action) -> float:
    start = time.perf_counter()
    action()
    return (time.perf_counter() - start) / STEPS * 1e6


def stepping() -> list[Row]:
    import mujoco

    import openbricks_native
    from openbricks_sim.shim import Shim
    from openbricks_sim.simulation import Simulation

    sim = Simulation("empty", "st3032")
    try:
        physics = sim.physics
        with Shim(sim):
            engine = sim.serial_bus(1)
            left, right = engine.adopt(1), engine.adopt(2, invert=True)
            db = openbricks_native.DriveBase(
                88, 138, left_io=engine.motor_io(left), right_io=engine.motor_io(right)
            )
            openbricks_native.motor_process.subscribe(db)
            db.drive(150, 20)  # a long arc: the controller works every tick
            physics.step(500)

            def bare():
                mujoco.set_mjcb_control(None)
                try:
                    mujoco.mj_step(physics.model, physics.data, nstep=STEPS)
                finally:
                    mujoco.set_mjcb_control(physics._callback)

            def controlled():
                physics.step(STEPS)

            bare_us, controlled_us = [], []
            for _ in range(ROUNDS):
                bare_us.append(_per_step_us(bare))
                controlled_us.append(_per_step_us(controlled))
    finally:
        sim.close()
    best_bare, best_controlled = min(bare_us), min(controlled_us)
    overhead = (best_controlled / best_bare - 1) * 100
    return [
        Row("bare mj_step, st3032 chassis", best_bare, "us/step", f"median {statistics.median(bare_us):.2f}"),
        Row(
            "controlled step (DriveBase + motor models)",
            best_controlled,
            "us/step",
            f"median {statistics.median(controlled_us):.2f}",
        ),
        Row("control overhead over bare", overhead, "%", "product bar: <= 30 %"),
        Row("controlled stepping real-time factor", 1000.0 / best_controlled, "x", "physics + control only"),
    ]


def program_run() -> list[Row]:
    from openbricks_sim.run import run_program

    result = run_program("bench_drive.py", source=PROGRAM, limit_ms=60_000)
    if result.exit != "finished":
        raise RuntimeError(f"the benchmark program ended with {result.exit}: {result.error}")
    return [
        Row(
            "program run real-time factor (ST3032Motor driver)",
            result.sim_ms / 1000 / result.wall_s,
            "x",
            f"{result.sim_ms} ms simulated in {result.wall_s:.2f} s, peak {result.peak_rss_mb} MB",
        )
    ]


def run() -> list[Row]:
    return stepping() + program_run()
