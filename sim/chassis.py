"""The simulated robots: a rigid two-wheel differential chassis with casters,
parameterised by wheel diameter and axle track, with mount points for the
sensors the manual's builds carry.

Frame: the robot starts facing +x, +y to its left, +z up. Both wheel hinges
turn about the body's +y axis, so a positive wheel angle rolls the robot
forward on either side; the mirrored mounting of a real right-hand servo is
the serial-bus emulation's business (a servo built with invert=True reads
the negated wheel angle), exactly as on the hub.
"""

import math
from dataclasses import dataclass, field

import mujoco

from .motors import JGB37_520, ST3032, MotorModel


@dataclass(frozen=True)
class SensorMounts:
    """Where sensors sit on the chassis, in mm from the axle midpoint (x forward, y left)."""

    color_mm: tuple[tuple[float, float], ...] = ((60.0, 20.0), (60.0, -20.0))
    qtr_x_mm: float = 70.0
    distance_mm: tuple[float, float] = (95.0, 0.0)
    sensor_height_mm: float = 8.0


@dataclass(frozen=True)
class ChassisSpec:
    name: str
    motor: MotorModel
    wheel_diameter_mm: float
    axle_track_mm: float
    body_mass_kg: float
    body_size_mm: tuple[float, float, float]  # length, width, height
    wheel_width_mm: float = 12.0
    wheel_mass_kg: float = 0.04
    mounts: SensorMounts = field(default_factory=SensorMounts)

    def with_geometry(self, wheel_diameter_mm=None, axle_track_mm=None) -> "ChassisSpec":
        return ChassisSpec(
            name=self.name,
            motor=self.motor,
            wheel_diameter_mm=wheel_diameter_mm or self.wheel_diameter_mm,
            axle_track_mm=axle_track_mm or self.axle_track_mm,
            body_mass_kg=self.body_mass_kg,
            body_size_mm=self.body_size_mm,
            wheel_width_mm=self.wheel_width_mm,
            wheel_mass_kg=self.wheel_mass_kg,
            mounts=self.mounts,
        )


CHASSIS = {
    # The manual's serial-bus starter robot (7.1: 88 mm wheels, 138 mm track).
    "st3032": ChassisSpec(
        name="st3032",
        motor=ST3032,
        wheel_diameter_mm=88.0,
        axle_track_mm=138.0,
        body_mass_kg=0.75,
        body_size_mm=(170.0, 110.0, 40.0),
    ),
    # The DC gear-motor build (2.7): JGB37-520 1:30 behind an H-bridge.
    "jgb37": ChassisSpec(
        name="jgb37",
        motor=JGB37_520,
        wheel_diameter_mm=65.0,
        axle_track_mm=120.0,
        body_mass_kg=0.95,
        body_size_mm=(170.0, 100.0, 45.0),
    ),
}

# Tyre contact: a stiff contact (time constant 4 ms, twice the 1 ms step, the stable minimum)
# with high impedance, so the tyre sinks about 0.01 mm under the robot's weight. MuJoCo puts the
# contact point halfway down that depth, so the sphere is grown by half of it and the wheel rolls
# on its nominal radius: odometry then matches travel to about 0.001 %.
TYRE_SOLREF_S = 0.004
TYRE_SOLIMP = (0.95, 0.99, 0.001, 0.5, 2.0)
TYRE_FRICTION = 1.0
TYRE_RADIUS_MARGIN_MM = 0.005

ROBOT_BODY = "robot"
WHEEL_JOINTS = ("left_wheel", "right_wheel")
IMU_SITE = "imu"


def color_site(index: int) -> str:
    return f"color_{index}"


QTR_SITE = "qtr"
DISTANCE_SITE = "distance"


def add_chassis(spec: mujoco.MjSpec, chassis: ChassisSpec, x_mm=0.0, y_mm=0.0, heading_deg=0.0, drop_mm=1.0):
    """Splice the robot into a world spec at (x_mm, y_mm), facing heading_deg (clockwise from +x).

    The axle starts drop_mm above its resting height; let it settle before relying on the pose.
    """
    mm = 0.001
    radius = chassis.wheel_diameter_mm / 2 * mm
    length, width, height = (v * mm for v in chassis.body_size_mm)
    yaw = -math.radians(heading_deg)  # clockwise-positive heading, counter-clockwise MuJoCo yaw
    robot = spec.worldbody.add_body(
        name=ROBOT_BODY,
        pos=[x_mm * mm, y_mm * mm, radius + drop_mm * mm],
        quat=[math.cos(yaw / 2), 0.0, 0.0, math.sin(yaw / 2)],
    )
    robot.add_freejoint(name="robot_free")
    # The body sits between the wheels, its underside clear of the floor.
    robot.add_geom(
        name="robot_body",
        type=mujoco.mjtGeom.mjGEOM_BOX,
        size=[length / 2, (chassis.axle_track_mm * mm - chassis.wheel_width_mm * mm) / 2 - 0.004, height / 2],
        pos=[0.0, 0.0, height / 2 - radius * 0.4],
        mass=chassis.body_mass_kg,
        rgba=[0.25, 0.3, 0.4, 1.0],
    )
    # Two low-friction ball casters fore and aft keep it level without steering it.
    for name, x in (("caster_front", length / 2 - 0.012), ("caster_rear", -length / 2 + 0.012)):
        robot.add_geom(
            name=name,
            type=mujoco.mjtGeom.mjGEOM_SPHERE,
            size=[0.006, 0, 0],
            pos=[x, 0.0, -radius + 0.006],
            mass=0.005,
            friction=[0.0, 0.0, 0.0],
            condim=1,
            priority=1,  # its own frictionless contact wins over the floor's (MuJoCo otherwise takes the max)
            rgba=[0.6, 0.6, 0.6, 1.0],
        )
    half_track = chassis.axle_track_mm * mm / 2
    motor = chassis.motor
    for joint, side in zip(WHEEL_JOINTS, (1.0, -1.0), strict=True):
        wheel = robot.add_body(name=joint, pos=[0.0, side * half_track, 0.0])
        # The gearbox's friction sits on the joint, where MuJoCo resolves Coulomb friction at rest
        # as a constraint (no chatter) and integrates viscous damping implicitly.
        wheel.add_joint(
            name=joint,
            type=mujoco.mjtJoint.mjJNT_HINGE,
            axis=[0.0, 1.0, 0.0],
            armature=motor.reflected_inertia_kgm2,
            frictionloss=motor.coulomb_friction_nm,
            damping=motor.viscous_friction_nm_per_rad_s,
        )
        # The tyre touches the floor as a sphere: one contact point straight below the axle, which
        # costs a fraction of a cylinder's multi-point contact, and a wheel never touches the mat
        # anywhere else. See TYRE_RADIUS_MARGIN_MM for its size. The cylinder is what you see.
        wheel.add_geom(
            name=f"{joint}_tyre",
            type=mujoco.mjtGeom.mjGEOM_SPHERE,
            size=[radius + TYRE_RADIUS_MARGIN_MM * mm, 0.0, 0.0],
            mass=chassis.wheel_mass_kg,
            condim=3,
            priority=1,
            friction=[TYRE_FRICTION, 0.0, 0.0],
            solref=[TYRE_SOLREF_S, 1.0],
            solimp=list(TYRE_SOLIMP),
            group=3,
            rgba=[0.1, 0.1, 0.1, 0.0],
        )
        wheel.add_geom(
            name=f"{joint}_rim",
            type=mujoco.mjtGeom.mjGEOM_CYLINDER,
            size=[radius, chassis.wheel_width_mm * mm / 2, 0.0],
            quat=[math.sqrt(0.5), math.sqrt(0.5), 0.0, 0.0],
            contype=0,
            conaffinity=0,
            mass=0.0,
            rgba=[0.1, 0.1, 0.1, 1.0],
        )
        spec.add_actuator(
            name=joint,
            target=joint,
            trntype=mujoco.mjtTrn.mjTRN_JOINT,
            ctrlrange=[-2 * chassis.motor.stall_torque_nm, 2 * chassis.motor.stall_torque_nm],
            ctrllimited=1,
        )
    mounts = chassis.mounts
    z = (mounts.sensor_height_mm * mm) - radius
    robot.add_site(name=IMU_SITE, pos=[0.0, 0.0, 0.0])
    for i, (cx, cy) in enumerate(mounts.color_mm):
        robot.add_site(name=color_site(i), pos=[cx * mm, cy * mm, z], size=[0.004, 0, 0])
    robot.add_site(name=QTR_SITE, pos=[mounts.qtr_x_mm * mm, 0.0, z], size=[0.004, 0, 0])
    dx, dy = mounts.distance_mm
    robot.add_site(name=DISTANCE_SITE, pos=[dx * mm, dy * mm, height / 2], size=[0.004, 0, 0])
    return robot
