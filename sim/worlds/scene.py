"""Physics settings every world shares, so the robot behaves the same on every mat."""

import mujoco

TIMESTEP_S = 0.001  # one physics step per 1 kHz control tick, as on the hub


def new_scene(name: str) -> mujoco.MjSpec:
    spec = mujoco.MjSpec()
    spec.modelname = name
    spec.option.timestep = TIMESTEP_S
    spec.option.integrator = mujoco.mjtIntegrator.mjINT_IMPLICITFAST
    # Elliptic friction cones with a high impedance ratio keep tyres from creeping under
    # traction, so odometry matches travel the way it does on a real mat.
    spec.option.cone = mujoco.mjtCone.mjCONE_ELLIPTIC
    spec.option.impratio = 10.0
    return spec
