"""One simulated hub on one robot in one world: physics, clock, board and the robot's wiring together.

    sim = Simulation(world="empty", chassis="st3032", seed=0)
    with Shim(sim):            # sim.shim: the program's machine/time/... modules
        ...                    # run hub code; time.sleep_ms() moves the robot
    sim.close()

The hub runtime's controllers run on openbricks_native.motor_process, which
the physics step ticks natively; firmware inside simulated devices (each
serial-bus servo's own speed loop) runs on the simulation's world_process.
"""

import time

import openbricks_native

from .clock import SimClock
from .job import INSTALL_HINT, SimulatorUnavailable
from .pacing import Pacer
from .shim.board import SimBoard

EMPTY_WORLD = "empty"


class Simulation:
    """The physics (MuJoCo, the world, the robot's wiring and sensors) is built when something first
    needs it: the program touching the hardware (`machine`, the serial bus), or a caller reading
    `physics`, `wiring`, `sensors`, `controller` or `world_process`. Until then time passes on the
    clock alone, so a program that only computes and prints never pays for MuJoCo, and the robot
    stands at rest where it starts, as it would have anyway."""

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
        self._place = (world, chassis, seed, start_mm_deg)
        self._geometry = (wheel_diameter_mm, axle_track_mm)
        self._rig = {"range_finder": range_finder, "bare_0x29": bare_0x29}
        self._built = None  # (physics, world_process, controller, wiring, sensors) once built
        self.build_s = None  # how long the build took, once built
        self._unbuilt_ms = 0  # simulated time that passed before the physics was built
        self.on_build = None  # (callable) run by the first hardware use, before the build (run.py)
        # A fresh hub: no controllers left over from an earlier run in this process.
        openbricks_native.motor_process.reset()
        self.clock = SimClock(self, limit_ms=limit_ms, epoch_ms=epoch_ms)
        self.pacer = None
        if speed is not None:
            self.pace(speed)
        self.board = SimBoard(self.clock, before_first_use=self._build)
        self.nvs = nvs if nvs is not None else {}

    # --- the physics, built on first use -------------------------------------------------------

    @property
    def built(self) -> bool:
        return self._built is not None

    @property
    def physics(self):
        return self._build()[0]

    @property
    def world_process(self):
        return self._build()[1]

    @property
    def controller(self):
        return self._build()[2]

    @property
    def wiring(self):
        return self._build()[3]

    @property
    def sensors(self):
        return self._build()[4]

    def _build(self):
        if self._built is not None:
            return self._built
        self.board.before_first_use = None
        started = time.perf_counter()
        try:
            if self.on_build is None:
                return self._build_now()
            with self.on_build():
                return self._build_now()
        finally:
            self.build_s = round(time.perf_counter() - started, 4)

    def _build_now(self):
        try:
            from .physics import Physics
            from .robot import wire
            from .sensors.rig import attach_sensors
        except ImportError as exc:
            if not _mujoco_failed(exc):
                raise
            raise SimulatorUnavailable(f"{INSTALL_HINT} ({exc})") from None

        world, chassis, seed, start_mm_deg = self._place
        physics = Physics(world, chassis, seed, start_mm_deg, *self._geometry)
        try:
            world_process = openbricks_native.MotorProcess()
            controller = physics.attach_control(world_process)
            controller.now_ms = self._unbuilt_ms
            wiring = wire(physics, self.board, world_process)
            sensors = attach_sensors(physics, self.board, seed, **self._rig)
        except BaseException:
            physics.close()
            raise
        self._built = (physics, world_process, controller, wiring, sensors)
        self.clock.follow(controller)
        return self._built

    # --- what the clock drives ----------------------------------------------------------------

    @property
    def now_ms(self) -> int:
        """Simulated milliseconds the physics has reached (the clock's, before it is built)."""
        if self._built is None:
            return self._unbuilt_ms
        return self._built[0].now_ms

    def step(self, n_ms: int) -> None:
        if self._built is None:
            self._unbuilt_ms += max(0, n_ms)
        else:
            self._built[0].step(n_ms)

    def resting_pose_mm_deg(self):
        """Before the physics is built, where the robot stands, if that is known without building it:
        on the empty world (no mission to score) it is the start pose, the origin unless given (as
        worlds.WORLDS["empty"] has it). None once built, or on any other world."""
        world, _chassis, _seed, start_mm_deg = self._place
        if self._built is not None or world != EMPTY_WORLD:
            return None
        return tuple(float(v) for v in start_mm_deg) if start_mm_deg is not None else (0.0, 0.0, 0.0)

    # --- pacing and devices -------------------------------------------------------------------

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
        from .sensors.rig import I2C_BUS, wire_bare_colour_sensor

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
        if self._built is not None:
            physics, world_process = self._built[0], self._built[1]
            world_process.reset()
            physics.close()


def _mujoco_failed(exc: ImportError) -> bool:
    """Whether this ImportError is MuJoCo's (not there, or there but not loading): anything else is a bug."""
    try:
        import mujoco  # noqa: F401 - the import is the question
    except ImportError:
        return True
    return False
