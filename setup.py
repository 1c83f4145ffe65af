"""Maps the source folders onto the installed package names and builds the host
extension of the C control cores; everything else is in pyproject.toml.

Installed import names all start with `openbricks`, while the tree keeps the
short folder names of the product layout (server/, sim/).
"""

from glob import glob

from setuptools import Extension, find_packages, setup

PACKAGE_FOLDERS = {"openbricks": "openbricks", "openbricks_server": "server", "openbricks_sim": "sim"}
# The example programs the console offers (openbricks_server.examples reads them from here when installed):
# the folder's own modules only, not its subfolders (computer-side scripts, the printed manual's listings).
EXAMPLES = {"openbricks_server.example_programs": "examples"}
NATIVE = "firmware/native"
# Emulated servos in C, for the simulator and the unix port's tests (not built into a hub).
EMULATION = f"{NATIVE}/user_c_modules/openbricks_bench"


def packages() -> list[str]:
    names = []
    for name, folder in PACKAGE_FOLDERS.items():
        names.append(name)
        names.extend(f"{name}.{sub}" for sub in find_packages(folder))
    return names + list(EXAMPLES)


setup(
    packages=packages(),
    package_dir={**PACKAGE_FOLDERS, **EXAMPLES},
    ext_modules=[
        Extension(
            "openbricks_native",
            sources=[
                *sorted(glob(f"{NATIVE}/*.c")),
                f"{NATIVE}/platform/hard_timer_posix.c",  # the hard tick's timer on a host
                *sorted(glob(f"{NATIVE}/bindings/cpython/*.c")),
            ],
            include_dirs=[NATIVE, f"{NATIVE}/bindings/cpython"],
            depends=sorted(glob(f"{NATIVE}/*.h")) + sorted(glob(f"{NATIVE}/bindings/cpython/*.h")),
            extra_compile_args=["-O2", "-std=gnu99", "-Wall", "-Wextra", "-Wno-missing-field-initializers"],
        ),
        # The simulator's per-step control path (sim/native). A top-level module rather than
        # openbricks_sim._mjcontrol: a private `build_ext --build-lib DIR` would otherwise create
        # DIR/openbricks_sim/ with no __init__.py, which shadows the real package for anyone who puts
        # DIR on PYTHONPATH. It needs no MuJoCo headers: it reaches mjData through the Python bindings.
        Extension(
            "openbricks_mjcontrol",
            # The emulated servo bus is the servo emulation the unix port's bench bus runs too, and
            # parses and answers packets with the firmware's own codec.
            sources=[*sorted(glob("sim/native/*.c")), f"{EMULATION}/emulated_servo.c", f"{NATIVE}/scs.c"],
            include_dirs=[NATIVE, f"{NATIVE}/bindings/cpython", EMULATION, "sim/native"],
            depends=[
                f"{NATIVE}/ob_types.h",
                f"{NATIVE}/scs.h",
                f"{NATIVE}/uart.h",
                f"{EMULATION}/emulated_servo.h",
                *sorted(glob("sim/native/*.h")),
                *sorted(glob(f"{NATIVE}/bindings/cpython/py_*.h")),
            ],
            extra_compile_args=["-O2", "-std=gnu99", "-Wall", "-Wextra", "-Wno-missing-field-initializers"],
        ),
        # The simulator's Python-time charge (sim/python_cost.py): a C profile function, because a
        # Python one would cost more host time than the control path it shares the process with.
        Extension(
            "openbricks_pycost",
            sources=["sim/native/python_cost/python_cost.c"],
            extra_compile_args=["-O2", "-std=gnu99", "-Wall", "-Wextra", "-Wno-missing-field-initializers"],
        ),
    ],
)
