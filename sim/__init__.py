"""openbricks_sim: MuJoCo worlds, the driver shim and virtual hubs that run hub programs unchanged.

The simulator never renders through MuJoCo's OpenGL contexts (the 3D view is viser in the browser),
so unless the user chose a backend, MuJoCo is told to load none: that skips importing GLFW, a good
part of every sim process's start-up. A simulation steps on one thread, so numpy's OpenBLAS is kept
to one too: by default it starts a thread per core that spins after each BLAS call, CPU taken from
the other simulations, virtual hubs and the console on the same machine.
"""

import os

os.environ.setdefault("MUJOCO_GL", "disable")
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
