"""The frozen modules of firmware/manifest.py, compiled with mpy-cross for the chip as the port's
build freezes them (tools/makemanifest.py: one .mpy per module, `-march` from the port).
"""

import sys
from pathlib import Path

from steps import CheckError, run

MANIFEST = Path(__file__).resolve().parents[1] / "manifest.py"
# ports/esp32/esp32_common.cmake: MICROPY_CROSS_FLAGS for the Xtensa chips (ESP32 and ESP32-S3).
CROSS_FLAGS = ["-march=xtensawin"]


def build_mpy_cross(micropython, out):
    """MicroPython's own mpy-cross, built from the same source tree the port is (once)."""
    binary = out / "mpy-cross"
    if not binary.is_file():
        run(["make", "-C", str(micropython / "mpy-cross"), "-j2", f"BUILD={out}"], "building mpy-cross")
    return binary


def manifest_files(micropython, board_dir):
    """(files to freeze as (source, target path), requirements the source trees do not hold)."""
    sys.path.insert(0, str(micropython / "tools"))
    try:
        import manifestfile
    finally:
        sys.path.pop(0)

    library = micropython / "lib" / "micropython-lib"
    unresolved = []

    class Manifest(manifestfile.ManifestFile):
        def require(self, name, *args, **kwargs):
            try:
                super().require(name, *args, **kwargs)
            except ValueError:
                unresolved.append(name)

    manifest = Manifest(
        manifestfile.MODE_FREEZE,
        {
            "MPY_DIR": str(micropython),
            "PORT_DIR": str(micropython / "ports" / "esp32"),
            "BOARD_DIR": str(board_dir),
            "MPY_LIB_DIR": str(library) if (library / "micropython").is_dir() else "",
        },
    )
    try:
        manifest.execute(str(MANIFEST))
    except manifestfile.ManifestFileError as err:
        raise CheckError(f"{MANIFEST}: {err}") from None
    files = [
        (Path(f.full_path), f.target_path)
        for f in manifest.files()
        if f.kind == manifestfile.KIND_FREEZE_AS_MPY or f.full_path.endswith(".py")
    ]
    return files, unresolved


def compile_frozen(mpy_cross, files, out):
    """mpy-cross each module; returns how many compiled, or raises with every module that did not."""
    problems = []
    for source, target_path in files:
        mpy = out / Path(target_path).with_suffix(".mpy")
        mpy.parent.mkdir(parents=True, exist_ok=True)
        command = [str(mpy_cross), "-o", str(mpy), "-s", target_path, *CROSS_FLAGS, str(source)]
        try:
            run(command, f"mpy-cross {source}")
        except CheckError as err:
            problems.append(str(err))
    if problems:
        raise CheckError("mpy-cross refused frozen modules:\n  " + "\n  ".join(problems))
    return len(files)
