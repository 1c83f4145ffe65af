"""Datasheet models of the drive motors the simulator puts on its chassis.

Each wheel motor is a DC motor behind a gearbox, seen at the output shaft:
torque = stall_torque * (duty - speed / no_load_speed), less Coulomb and
viscous friction. The figures are the manual's: the ST-3032 (148 RPM =
888 deg/s no load at 12 V, 10 kg.cm stall, 1/205 gearing, 4096-count
magnetic encoder) and the JGB37-520 1:30 (11-PPR encoder x 30 x 4 = 1320
edges per output turn; 12 V catalogue figures of the 1:30 variant).
"""

import math
from dataclasses import dataclass

KGCM_TO_NM = 0.0980665


@dataclass(frozen=True)
class MotorModel:
    name: str
    no_load_speed_dps: float
    stall_torque_nm: float
    counts_per_rev: int
    gear_ratio: float
    # Rotor inertia reflected through the gearbox (kg m^2): J_rotor * ratio^2.
    reflected_inertia_kgm2: float
    coulomb_friction_nm: float
    viscous_friction_nm_per_dps: float

    @property
    def back_emf_speed_dps(self) -> float:
        """The speed at which back-EMF alone cancels full duty.

        A datasheet's no-load speed is measured with the gearbox's own friction
        present, so the electrical model must spin a little faster than that for
        the shaft, friction included, to reach it at 100 % duty:
        stall * (1 - v / v_emf) = coulomb + viscous * v at v = no_load_speed.
        """
        v = self.no_load_speed_dps
        drag = self.coulomb_friction_nm + self.viscous_friction_nm_per_dps * v
        return v * self.stall_torque_nm / (self.stall_torque_nm - drag)

    @property
    def viscous_friction_nm_per_rad_s(self) -> float:
        return self.viscous_friction_nm_per_dps * 180.0 / math.pi

    def torque_nm(self, duty_pct: float, speed_dps: float) -> float:
        """Electrical output torque for a duty command at the present shaft speed (back-EMF included).

        Friction is not in here: the chassis puts it on the wheel joint, where
        the physics engine resolves Coulomb friction at rest without chatter.
        """
        duty = max(-100.0, min(100.0, duty_pct)) / 100.0
        return self.stall_torque_nm * (duty - speed_dps / self.back_emf_speed_dps)


ST3032 = MotorModel(
    name="ST-3032",
    no_load_speed_dps=888.0,
    stall_torque_nm=10.0 * KGCM_TO_NM,
    counts_per_rev=4096,
    gear_ratio=205.0,
    reflected_inertia_kgm2=2.0e-9 * 205.0**2,
    # Back-driving a 1:205 spur train takes about half a kg.cm: a coasting robot stops within a few cm.
    coulomb_friction_nm=0.05,
    viscous_friction_nm_per_dps=2.0e-5,
)

JGB37_520 = MotorModel(
    name="JGB37-520 1:30",
    no_load_speed_dps=333.0 * 6.0,
    stall_torque_nm=4.5 * KGCM_TO_NM,
    counts_per_rev=1320,
    gear_ratio=30.0,
    reflected_inertia_kgm2=8.0e-8 * 30.0**2,
    coulomb_friction_nm=0.008,
    viscous_friction_nm_per_dps=1.0e-5,
)
