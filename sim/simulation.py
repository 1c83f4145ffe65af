"""One simulated hub on one robot in one world: physics, clock, board and the robot's wiring together.

    sim = Simulation(world="empty", chassis="st3032", seed=0)
    with Shim(sim):            # sim.shim: the program's machine/time/... modules
        ...                    # run hub code; time.sleep_ms() moves the robot
    sim.close()

The hub runtime's controllers run on openbricks_native.motor_process, which
the physics step ticks natively; firmware inside simulated devices (each
serial-bus servo's own speed loop) runs on the simulation's world_process.
"""

import openbricks_native

from .clock import SimClock
from .pacing import Pacer
from .physics import Physics
from .robot import wire
from .sensors.rig import I2C_BUS, attach_sensors, wire_bare_colour_sensor
from .shim.board import SimBoard


class Simulation:
    def __init__(
        self,
        world="empty",
        chassis="st3032",
        seed=0,
        start_mm_deg=None,
        speed=None,
        limit_ms=None,
        epoch_ms=None,
        nvs=None,
        wheel_diameter_mm=None,
        axle_track_mm=None,
        range_finder="vl53l0x",
        bare_0x29=None,
    ):
        """speed: a real-time factor to pace at (None: as fast as the CPU allows, no pacer at all).
        `range_finder` and `bare_0x29` choose the sensor rig's parts (see sensors/rig.py)."""
        self.physics = Physics(world, chassis, seed, start_mm_deg, wheel_diameter_mm, axle_track_mm)
        try:
            # A fresh hub: no controllers left over from an earlier run in this process.
            openbricks_native.motor_process.reset()
            self.world_process = openbricks_native.MotorProcess()
            self.controller = self.physics.attach_control(self.world_process)
            self.clock = SimClock(self.physics, limit_ms=limit_ms, epoch_ms=epoch_ms)
            self.pacer = None
            if speed is not None:
                self.pace(speed)
            self.board = SimBoard(self.clock)
            self.nvs = nvs if nvs is not None else {}
            self.wiring = wire(self.physics, self.board, self.world_process)
            self.sensors = attach_sensors(
                self.physics, self.board, seed, range_finder=range_finder, bare_0x29=bare_0x29
            )
        except BaseException:
            self.physics.close()
            raise

    def pace(self, speed=1.0, **options):
        """Pace this simulation from now on with a new Pacer (pacing.py; options: on_frame,
        frame_hz, wakeup), replacing the one it had: one pacer per clock, or they would wait
        on each other."""
        if self.pacer is not None:
            self.pacer.stop()
        self.pacer = Pacer(self.clock, speed=speed, **options)
        self.pacer.start()
        return self.pacer

    @classmethod
    def for_job(cls, job, paced=True):
        """The simulation a SimJob runs in; paced=False leaves the pace to someone else (a viewer)."""
        return cls(
            job.world,
            job.chassis,
            job.seed,
            job.start_mm_deg,
            speed=job.speed if paced else None,
            limit_ms=job.limit_ms,
            range_finder=job.range_finder,
            bare_0x29=job.bare_0x29,
        )

    def wire_bare_colour_sensor(self, i2c_key):
        """The program built a TCS34725 straight on I2C bus `i2c_key`: wire one there (bus 0 only).

        False when the rig already has another part at 0x29 on that bus (--bare-0x29 said so)."""
        if i2c_key != I2C_BUS:
            return True
        return wire_bare_colour_sensor(self.sensors, self.physics, self.board, self.physics.seed)

    def serial_bus(self, uart_id, tx=None, rx=None, baud=1_000_000, dir_pin=None):
        """`_openbricks_native.serial_bus(uart_id, ...)`: the engine a DriveBase adopts serial-bus wheels onto
        (the simulated robot's wiring is fixed, so the pins are the program's business only)."""
        return self.wiring.serial_bus(uart_id)

    def close(self):
        """Stop every controller and release the physics callback (idempotent)."""
        if self.pacer is not None:
            self.pacer.stop()
        openbricks_native.motor_process.reset()
        self.world_process.reset()
        self.physics.close()
