"""Build MicroPython's unix port with the project's user C modules: the real `_openbricks_native` on a host.

    python firmware/unix_micropython.py --src SRC --build DIR     # prints the interpreter's path

SRC is a MicroPython source release tarball (`micropython-*.tar.gz`, as in the `shared/micropython/`
folder beside the checkout) or a MicroPython checkout (a folder with `py/mpconfig.h`). A tarball is
unpacked once into DIR/src; the port builds into DIR/port (MicroPython's make is incremental, so a
rebuild after editing firmware/native recompiles only what changed) and the interpreter is copied
to DIR/micropython. `make micropython` runs this; `make test` runs the runtime's tests on the result.
"""

import argparse
import shutil
import subprocess
import sys
import tarfile
from pathlib import Path

FIRMWARE = Path(__file__).resolve().parent
USER_C_MODULES = FIRMWARE / "native" / "user_c_modules"
# The libraries of these features are git submodules, which a source release without them lacks;
# FROZEN_MANIFEST= skips freezing micropython-lib (also a submodule).
PORT_OPTIONS = ("MICROPY_PY_BTREE=0", "MICROPY_PY_FFI=0", "MICROPY_PY_SSL=0", "FROZEN_MANIFEST=")
BUILD_LIMIT_S = 1800


class BuildError(Exception):
    """The build could not run or failed; the message says which step and how to fix it."""


def source_tree(src, build_dir):
    """The MicroPython source folder for `src` (a tarball is unpacked under build_dir/src once)."""
    src = Path(src).expanduser().resolve()
    if src.is_dir():
        if not (src / "py" / "mpconfig.h").is_file() or not (src / "ports" / "unix").is_dir():
            raise BuildError(f"{src} is not a MicroPython source tree (no py/mpconfig.h or ports/unix)")
        return src
    if not src.is_file():
        raise BuildError(
            f"MicroPython source not found at {src}: give a source release tarball or a checkout "
            "(make MICROPY_SRC=/path/to/micropython)"
        )
    unpacked = build_dir / "src"
    stamp = unpacked / (src.name + ".unpacked")
    if not stamp.is_file():
        shutil.rmtree(unpacked, ignore_errors=True)
        unpacked.mkdir(parents=True)
        try:
            with tarfile.open(src) as archive:
                archive.extractall(unpacked, filter="data")
        except (tarfile.TarError, OSError) as err:
            raise BuildError(f"could not unpack {src}: {err}") from None
        stamp.touch()
    trees = [p.parent.parent for p in unpacked.glob("*/py/mpconfig.h")]
    if len(trees) != 1:
        raise BuildError(f"{src} does not hold one MicroPython source tree (found {len(trees)})")
    return trees[0]


def _run(step):
    try:
        result = subprocess.run(step, capture_output=True, text=True, timeout=BUILD_LIMIT_S)
    except subprocess.TimeoutExpired:
        raise BuildError(f"{' '.join(step)} did not finish within {BUILD_LIMIT_S} s") from None
    if result.returncode != 0:
        raise BuildError(f"{' '.join(step)} failed:\n{(result.stdout + result.stderr)[-6000:]}")


def build(src, build_dir, jobs=2):
    """Build (or bring up to date) the unix interpreter with `_openbricks_native`; returns its path."""
    build_dir = Path(build_dir).resolve()
    build_dir.mkdir(parents=True, exist_ok=True)
    tree = source_tree(src, build_dir)
    port_build = build_dir / "port"
    _run(["make", "-C", str(tree / "mpy-cross"), f"-j{jobs}", f"BUILD={build_dir / 'mpy-cross'}"])
    _run(
        [
            "make",
            "-C",
            str(tree / "ports" / "unix"),
            f"-j{jobs}",
            "VARIANT=standard",
            f"BUILD={port_build}",
            f"MICROPY_MPYCROSS={build_dir / 'mpy-cross' / 'mpy-cross'}",
            f"USER_C_MODULES={USER_C_MODULES}",
            *PORT_OPTIONS,
        ]
    )
    interpreter = build_dir / "micropython"
    shutil.copy2(port_build / "micropython", interpreter)
    return interpreter


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--src", required=True, help="MicroPython source tarball or checkout")
    parser.add_argument("--build", required=True, help="build folder (the interpreter lands in it)")
    parser.add_argument("--jobs", type=int, default=2)
    args = parser.parse_args(argv)
    try:
        print(build(args.src, args.build, args.jobs))
    except BuildError as err:
        sys.exit(f"building the unix MicroPython: {err}")


if __name__ == "__main__":
    main()
