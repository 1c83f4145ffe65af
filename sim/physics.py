"""One simulated robot in one world: the compiled MuJoCo model, its pose, and its wheels.

`Physics` compiles a world with a chassis spliced in, settles the robot on
the floor, and then advances in whole milliseconds (one MuJoCo step each).
Once `attach_control()` has run, every step also runs the native control
path (openbricks_mjcontrol): the hub's motor_process and the world's device
firmware are ticked and the wheel motors apply their torque, all in C, so
`step(n)` is one `mujoco.mj_step(nstep=n)` call however large n is.

Units are the manual's: millimetres, degrees, heading clockwise-positive from
+x (MuJoCo's yaw is counter-clockwise, so heading_deg = -yaw).
"""

import ctypes
import glob
import math
import os
from dataclasses import dataclass

import mujoco

from .chassis import CHASSIS, ROBOT_BODY, WHEEL_JOINTS, ChassisSpec, add_chassis
from .worlds import World, resolve

# The robot is dropped this far above its resting height and settled before time starts.
_SETTLE_MS = 200
_DROP_MM = 0.5

# MuJoCo's mjfGeneric: void (*)(const mjModel*, mjData*).
_CONTROL_CALLBACK = ctypes.CFUNCTYPE(None, ctypes.c_void_p, ctypes.c_void_p)


@dataclass(frozen=True)
class Pose:
    x_mm: float
    y_mm: float
    heading_deg: float  # clockwise from +x, within (-180, 180]


class ControlBusyError(RuntimeError):
    """Another Physics in this process already owns MuJoCo's (process-wide) control callback."""


_control_owner = [None]  # the Physics whose controller the process-wide callback serves


class Physics:
    """A world, a robot on it, and (after attach_control) its motors.

    chassis is a name from CHASSIS or a ChassisSpec; wheel_diameter_mm and
    axle_track_mm override its geometry; start_mm_deg = (x, y, heading)
    overrides the world's start pose.
    """

    def __init__(
        self,
        world="empty",
        chassis="st3032",
        seed=0,
        start_mm_deg=None,
        wheel_diameter_mm=None,
        axle_track_mm=None,
    ):
        _mujoco_library()
        self.world: World = resolve(world) if isinstance(world, str) else world
        spec = chassis if isinstance(chassis, ChassisSpec) else _chassis(chassis)
        self.chassis: ChassisSpec = spec.with_geometry(wheel_diameter_mm, axle_track_mm)
        self.seed = seed
        x_mm, y_mm, heading_deg = start_mm_deg if start_mm_deg is not None else self.world.start_mm_deg
        mj_spec = self.world.build(seed)
        add_chassis(mj_spec, self.chassis, x_mm, y_mm, heading_deg, drop_mm=_DROP_MM)
        self.model = mj_spec.compile()
        self.data = mujoco.MjData(self.model)
        self._robot = self.model.body(ROBOT_BODY).id
        self._free_qpos = self.model.jnt_qposadr[self.model.joint("robot_free").id]
        self.wheel_joints = tuple(self.model.joint(name) for name in WHEEL_JOINTS)
        self.controller = None
        self._callback = None
        self._settle()

    # --- state -----------------------------------------------------------------------------

    @property
    def now_ms(self) -> int:
        """Simulated milliseconds since the robot was put down."""
        if self.controller is not None:
            return self.controller.now_ms
        return self._bare_ms

    def pose(self) -> Pose:
        q = self._free_qpos
        x, y = self.data.qpos[q], self.data.qpos[q + 1]
        w, qx, qy, qz = self.data.qpos[q + 3 : q + 7]
        yaw = math.atan2(2.0 * (w * qz + qx * qy), 1.0 - 2.0 * (qy * qy + qz * qz))
        heading = -math.degrees(yaw)
        if heading <= -180.0:
            heading += 360.0
        return Pose(float(x) * 1000.0, float(y) * 1000.0, heading)

    def wheel_angle_deg(self, index: int) -> float:
        """True angle of wheel `index` (0 left, 1 right), positive rolling forward."""
        return math.degrees(self.data.qpos[self.wheel_joints[index].qposadr[0]])

    # --- stepping --------------------------------------------------------------------------

    def step(self, n: int = 1) -> None:
        """Advance n milliseconds: controlled when attach_control() has run, bare physics otherwise."""
        if n <= 0:
            return
        if self.controller is not None:
            self.controller.step(n)
        else:
            mujoco.mj_step(self.model, self.data, nstep=n)
            self._bare_ms += n

    def attach_control(self, world_process=None):
        """Put the robot's wheels under the native control path and return the Controller.

        world_process is the MotorProcess that runs firmware inside simulated
        devices (a serial-bus servo's own speed loop); the hub runtime's
        controllers run on openbricks_native.motor_process. MuJoCo's control
        callback is process-wide, so only one Physics per process may hold it.
        """
        openbricks_mjcontrol = _native_control()
        if self.controller is not None:
            return self.controller
        if self._bare_ms:
            raise RuntimeError("attach_control() must come before any bare step(): the clocks would disagree")
        owner = _control_owner[0]
        if owner is not None and owner is not self:
            raise ControlBusyError(
                "another simulated robot in this process already runs the physics control callback; "
                "close() it first (MuJoCo's control callback is process-wide)"
            )
        controller = openbricks_mjcontrol.Controller(self.model, self.data, _mj_step_address(), world_process)
        motor = self.chassis.motor
        for joint in self.wheel_joints:
            controller.add_wheel(
                joint.qposadr[0],
                joint.dofadr[0],
                self.model.actuator(joint.name).id,
                motor.stall_torque_nm,
                motor.back_emf_speed_dps,
            )
        controller.activate()
        self._callback = _CONTROL_CALLBACK(openbricks_mjcontrol.control_callback_address())
        mujoco.set_mjcb_control(self._callback)
        _control_owner[0] = self
        self.controller = controller
        return controller

    def servo_wire(self):
        """An emulated serial-bus wire on this robot's control path: servos attached to it answer the
        firmware's bus engine in SCS packets with 1 Mbaud half-duplex byte timing on simulated time."""
        return _native_control().ServoWire(self.attach_control())

    def wheel_io(self, index: int, sign: int = 1, counts_per_rev=None):
        """A native motor IO onto wheel `index` (0 left, 1 right) in a frame mirrored by sign."""
        openbricks_mjcontrol = _native_control()
        if self.controller is None:
            raise RuntimeError("wheel_io() needs attach_control() first")
        counts = counts_per_rev if counts_per_rev is not None else self.chassis.motor.counts_per_rev
        return openbricks_mjcontrol.WheelIO(self.controller, index, sign, float(counts))

    def close(self) -> None:
        """Release the process-wide control callback (idempotent)."""
        if _control_owner[0] is self:
            mujoco.set_mjcb_control(None)
            _control_owner[0] = None
        if self.controller is not None:
            self.controller.deactivate()
        self._callback = None

    # --- internals -------------------------------------------------------------------------

    def _settle(self) -> None:
        """Let the robot come to rest on its wheels, then start the clock at zero."""
        mujoco.mj_step(self.model, self.data, nstep=_SETTLE_MS)
        self.data.time = 0.0
        self.data.qvel[:] = 0.0
        self._bare_ms = 0


def _chassis(name: str) -> ChassisSpec:
    try:
        return CHASSIS[name]
    except KeyError:
        known = ", ".join(sorted(CHASSIS))
        raise ValueError(f"unknown chassis {name!r}: use one of {known}") from None


def _mujoco_library() -> ctypes.CDLL:
    """MuJoCo's C library, the one the mujoco package loaded (one MuJoCo in the process).

    The first call also clears MuJoCo's timer callback, which the mujoco package sets to a clock read:
    MuJoCo then reads the clock a few dozen times per step for its profiling timers (mjData.timer),
    about a tenth of a step's cost, and the simulator never reads them."""
    if not _library:
        folder = os.path.dirname(mujoco.__file__)
        names = ("libmujoco.so*", "libmujoco*.dylib", "mujoco.dll")
        found = [
            path
            for name in names
            for path in sorted(glob.glob(os.path.join(folder, "**", name), recursive=True))
        ]
        if not found:
            raise ImportError(f"MuJoCo's library is not inside its package at {folder}: reinstall mujoco")
        library = ctypes.CDLL(found[0])
        ctypes.c_void_p.in_dll(library, "mjcb_time").value = None
        _library.append(library)
    return _library[0]


_library: list[ctypes.CDLL] = []


def _mj_step_address() -> int:
    """MuJoCo's C `mj_step`, which the controller calls itself (sim/native/mjcontrol.c says why)."""
    return ctypes.cast(_mujoco_library().mj_step, ctypes.c_void_p).value


def _native_control():
    """The native control path, with a clear message when the two extensions do not match."""
    try:
        import openbricks_mjcontrol
    except (ImportError, AttributeError) as exc:
        import openbricks_native

        raise ImportError(
            f"the simulator's native control path (openbricks_mjcontrol) cannot load against "
            f"{openbricks_native.__file__}: {exc}. The two extensions come from one build: run "
            "`python setup.py build_ext --inplace` (or `make test`), or put a fresh private build first "
            "on PYTHONPATH"
        ) from exc
    return openbricks_mjcontrol
