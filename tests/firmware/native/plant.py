"""Plant model of one geared motor driving one wheel, for closed-loop tests of the control cores.

The controllers under test only ever see what a hub sees: a duty command going out and a quantised
encoder angle coming back. This module supplies the physics in between, with the effects that make a
controller work for its living:

* **DC motor torque-speed line.** A brushed motor on an H-bridge delivers, at the gearbox output,
  ``stall_torque * (duty/100 - speed/no_load_speed)``. At 100 % duty and no load the shaft settles at
  ``no_load_speed_dps`` (less the few per cent that the friction below costs); the
  ``-speed/no_load_speed`` term is the back-EMF, which acts as a strong speed-proportional damping.
  Duty 0 therefore brakes (the bridge shorts the winding); coasting (``step(None, dt)``) opens the
  winding: no motor torque and no back-EMF damping. Armature inductance is neglected (its time
  constant is well under a millisecond for these motors, far below the 1 ms control period).
* **Reflected inertia.** The rotor inertia multiplied by the gear ratio squared dominates a small geared
  servo; the wheel and the share of the robot's mass that this wheel accelerates (``m * r**2``, rolling
  without slip) add to it. Everything is expressed at the gearbox output.
* **Viscous friction** proportional to speed, and **Coulomb friction** of constant magnitude opposing
  motion, with stiction: at rest the shaft stays put until the drive torque exceeds the break-away
  torque, and a shaft that friction brings to a stop within a sub-step stays stopped instead of
  chattering around zero.
* **Effectiveness**: a factor on the motor torque (0.9 models a weak or slipping wheel that delivers 90 %
  of the torque of its twin).
* **External load**: a disturbance torque (``load_torque_nm``) and a hard block (``blocked``, a wheel
  pushed into a wall).
* **Encoder quantisation**: ``encoder_deg`` is the true angle floored to whole counts of a
  ``counts_per_rev`` encoder at the output, like a magnetic encoder read by the servo's MCU.

Integration is semi-implicit Euler over sub-steps of at most ``max_substep_s``: the linear damping terms
(back-EMF and viscous) are integrated implicitly, so the model is stable for any step size, and the
sub-steps keep the friction transitions sharp.

The defaults model a Feetech ST-3032 (888 deg/s no load and 10 kg*cm stall torque at the output, 1:205
gearing) carrying half of a 1 kg two-wheeled robot on a 56 mm wheel. Its mechanical time constant
``J * no_load_speed / stall_torque`` comes out near 30 ms, typical of small geared servos.
"""

import math

KG_CM_TO_NM = 0.0980665
"""Torque unit conversion: servo datasheets rate stall torque in kg*cm."""


class WheelPlant:
    """A geared DC motor plus wheel, driven by duty and read through a quantised encoder.

    Angles and speeds are at the gearbox output, in degrees and degrees per second; torques are in N*m
    at the output; inertia in kg*m**2.
    """

    def __init__(
        self,
        *,
        no_load_speed_dps: float = 888.0,
        stall_torque_nm: float = 10.0 * KG_CM_TO_NM,
        gear_ratio: float = 205.0,
        rotor_inertia_kgm2: float = 4.0e-8,
        wheel_diameter_mm: float = 56.0,
        wheel_mass_kg: float = 0.02,
        carried_mass_kg: float = 0.5,
        viscous_nm_per_dps: float = 5.0e-6,
        coulomb_nm: float = 0.01,
        static_nm: float = 0.015,
        effectiveness: float = 1.0,
        counts_per_rev: int = 4096,
        max_substep_s: float = 2.5e-4,
        angle_deg: float = 0.0,
    ) -> None:
        """Build a plant at rest at ``angle_deg``.

        ``carried_mass_kg`` is the share of the robot's mass that this wheel accelerates (half of a
        1 kg robot by default); set it to 0 for a motor spinning a bare wheel in the air.
        ``static_nm`` is the break-away torque at rest and must be at least ``coulomb_nm``.
        """
        if no_load_speed_dps <= 0 or stall_torque_nm <= 0:
            raise ValueError("no_load_speed_dps and stall_torque_nm must be > 0")
        if static_nm < coulomb_nm or coulomb_nm < 0 or viscous_nm_per_dps < 0:
            raise ValueError("need 0 <= coulomb_nm <= static_nm and viscous_nm_per_dps >= 0")
        if not 0.0 <= effectiveness <= 1.5:
            raise ValueError(f"effectiveness must be within 0..1.5, got {effectiveness}")
        if counts_per_rev < 1:
            raise ValueError(f"counts_per_rev must be >= 1, got {counts_per_rev}")
        self.no_load_speed_dps = float(no_load_speed_dps)
        self.stall_torque_nm = float(stall_torque_nm)
        self.viscous_nm_per_dps = float(viscous_nm_per_dps)
        self.coulomb_nm = float(coulomb_nm)
        self.static_nm = float(static_nm)
        self.effectiveness = float(effectiveness)
        self.counts_per_rev = int(counts_per_rev)
        self.max_substep_s = float(max_substep_s)
        radius_m = wheel_diameter_mm / 2000.0
        self.inertia_kgm2 = (
            rotor_inertia_kgm2 * gear_ratio**2
            + 0.5 * wheel_mass_kg * radius_m**2
            + carried_mass_kg * radius_m**2
        )
        self.angle_deg = float(angle_deg)
        self.speed_dps = 0.0
        self.duty_pct = 0.0
        self.load_torque_nm = 0.0
        """External disturbance torque at the output (positive pushes toward increasing angle)."""
        self.blocked = False
        """When True the wheel is held rigidly (pushed into a wall): it cannot turn either way."""
        self.coasting = False
        """True while the last step coasted (winding open)."""
        self.time_s = 0.0

    @property
    def back_emf_nm_per_dps(self) -> float:
        """Damping slope of the torque-speed line: torque lost per deg/s of shaft speed at any duty."""
        return self.stall_torque_nm / self.no_load_speed_dps

    def motor_torque_nm(self, duty_pct: float, speed_dps: float) -> float:
        """Torque the motor delivers to the wheel at this duty and speed (after effectiveness)."""
        duty = max(-100.0, min(100.0, duty_pct)) / 100.0
        return self.effectiveness * self.stall_torque_nm * (duty - speed_dps / self.no_load_speed_dps)

    @property
    def encoder_deg(self) -> float:
        """The angle as the encoder reports it: floored to whole counts."""
        counts = math.floor(self.angle_deg * self.counts_per_rev / 360.0)
        return counts * 360.0 / self.counts_per_rev

    def step(self, duty_pct: float | None, dt_s: float) -> None:
        """Advance the plant by ``dt_s`` seconds with ``duty_pct`` (clamped to -100..100) applied.

        ``None`` coasts: the bridge releases the winding, so the wheel only feels friction and load.
        """
        if dt_s < 0:
            raise ValueError(f"dt_s must be >= 0, got {dt_s}")
        self.coasting = duty_pct is None
        self.duty_pct = 0.0 if duty_pct is None else max(-100.0, min(100.0, float(duty_pct)))
        substeps = max(1, math.ceil(dt_s / self.max_substep_s))
        h = dt_s / substeps
        for _ in range(substeps):
            self._substep(h)
        self.time_s += dt_s

    def _substep(self, h: float) -> None:
        if self.blocked:
            self.speed_dps = 0.0
            return
        rad = math.pi / 180.0
        inertia_deg = self.inertia_kgm2 * rad  # N*m per (deg/s^2)
        # Torque that does not depend on speed: the duty part of the motor line plus the external load.
        drive_nm = self.effectiveness * self.stall_torque_nm * self.duty_pct / 100.0 + self.load_torque_nm
        damping = self.viscous_nm_per_dps
        if not self.coasting:
            damping += self.effectiveness * self.back_emf_nm_per_dps
        v = self.speed_dps
        if v == 0.0:
            if abs(drive_nm) <= self.static_nm:
                return  # stiction holds the shaft
            friction_nm = -math.copysign(self.coulomb_nm, drive_nm)
        else:
            friction_nm = -math.copysign(self.coulomb_nm, v)
        # Implicit in the damping term: v' = (v + h*T/J) / (1 + h*c/J), stable for any h.
        v_new = (v + h * (drive_nm + friction_nm) / inertia_deg) / (1.0 + h * damping / inertia_deg)
        if v != 0.0 and (v_new == 0.0 or math.copysign(1.0, v_new) != math.copysign(1.0, v)):
            # Friction (or a reversing drive) crossed zero speed inside this sub-step: stop at zero, and
            # let the next sub-step decide from rest whether the drive breaks stiction the other way.
            self.angle_deg += 0.5 * v * h
            self.speed_dps = 0.0
            return
        self.angle_deg += 0.5 * (v + v_new) * h
        self.speed_dps = v_new
