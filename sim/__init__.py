"""openbricks_sim: MuJoCo worlds, the driver shim and virtual hubs that run hub programs unchanged.

The simulator never renders through MuJoCo's OpenGL contexts (the 3D view is viser in the browser),
so unless the user chose a backend, MuJoCo is told to load none: that skips importing GLFW, a good
part of every sim process's start-up.
"""

import os

os.environ.setdefault("MUJOCO_GL", "disable")
