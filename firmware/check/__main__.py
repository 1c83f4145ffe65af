"""make firmware-check: every C file of the hub image compiled for Xtensa against ESP-IDF 5.5.4 and
MicroPython 1.28's esp32 port, and every frozen module compiled with mpy-cross for the chip.

    python firmware/check [--target esp32|esp32s3 ...] [--only FILE ...] [--build DIR]
                          [--boards DIR] [--idf TREE_OR_ARCHIVE] [--micropython TREE_OR_ARCHIVE]

For each target: sdkconfig.h from ESP-IDF's Kconfig files and the board's fragments (sdkconfig.py),
the include path from ESP-IDF's components (include_path.py), MicroPython's generated headers
(genhdr.py), then the compiler with the port's flags and -Werror (flags.py, compile.py), and the
frozen modules (frozen.py). Prints one line per target; exits 1 with the compiler's own messages
(file:line) on any error or warning. --only compiles just the given files (the rest still runs).
It cannot link an image: that needs Espressif's toolchain and the Bluetooth libraries.
"""

import argparse
import shutil
import sys
import time
from pathlib import Path

import compile as compiler_step
import flags
import frozen
import genhdr
import include_path
import sdkconfig
import sources
from steps import CheckError

REPO = Path(__file__).resolve().parents[2]
TARGETS = ("esp32", "esp32s3")


def _check_target(target, trees, build, boards, only, mpy_cross):
    started = time.monotonic()
    out = build / target
    board_dir = boards / f"openbricks_{target}"
    port = trees.micropython / "ports" / "esp32"
    config = sdkconfig.generate(trees, target, sdkconfig.board_fragments(board_dir, port), out / "config")
    includes = include_path.component_includes(trees, target, config, out / "config")
    compiler, cpp_flags, c_flags = flags.command_line(trees, target, config, includes, out, board_dir)
    genhdr.generate(trees.micropython, compiler, cpp_flags, genhdr.binding_sources(flags.MODULE_DIR), out)
    objects = out / "obj"
    if not only:
        shutil.rmtree(objects, ignore_errors=True)
    todo = only or compiler_step.firmware_sources()
    outcome = compiler_step.compile_all(compiler, cpp_flags, [*c_flags, "-Werror"], todo, objects)
    for message in outcome.messages:
        print(message, file=sys.stderr)
    frozen_count, unresolved = 0, []
    if not only:
        files, unresolved = frozen.manifest_files(trees.micropython, board_dir)
        shutil.rmtree(out / "frozen", ignore_errors=True)
        frozen_count = frozen.compile_frozen(mpy_cross, files, out / "frozen")
    seconds = time.monotonic() - started
    line = (
        f"firmware-check {target}: {len(outcome.compiled)} of {len(todo)} C files compiled for Xtensa, "
        f"{outcome.warnings} warnings"
    )
    if not only:
        line += f", {frozen_count} frozen modules (mpy-cross {' '.join(frozen.CROSS_FLAGS)})"
        if unresolved:
            line += f", not in the source trees: require({', '.join(map(repr, unresolved))})"
    print(f"{line}, {seconds:.1f} s", flush=True)
    return not outcome.failed and outcome.warnings == 0


def main(argv=None):
    parser = argparse.ArgumentParser(prog="firmware-check", description=__doc__.split("\n\n")[0])
    parser.add_argument("--target", action="append", choices=TARGETS, help="a chip to check (default: both)")
    parser.add_argument("--only", action="append", type=Path, metavar="FILE", help="compile only this C file")
    parser.add_argument("--build", type=Path, default=REPO / "build" / "firmware-check")
    parser.add_argument(
        "--boards",
        type=Path,
        default=REPO / "firmware" / "boards",
        help="the board definitions (default: firmware/boards)",
    )
    parser.add_argument("--idf", help="ESP-IDF v5.5.4: a tree or source archive (default: shared/esp32/)")
    parser.add_argument("--micropython", help="MicroPython v1.28.0 with its esp32 port: a tree or archive")
    args = parser.parse_args(argv)
    for path in args.only or []:
        if not path.is_file():
            parser.error(f"--only {path}: no such file")
    try:
        build = args.build.resolve()
        trees = sources.trees(build / "src", args.idf, args.micropython)
        for gap, cost in sources.ARCHIVE_GAPS.items():
            print(f"firmware-check: not in the ESP-IDF archive, so not checked: {gap}: {cost}")
        mpy_cross = None if args.only else frozen.build_mpy_cross(trees.micropython, build / "mpy-cross")
        ok = True
        for target in args.target or TARGETS:
            ok = _check_target(target, trees, build, args.boards.resolve(), args.only, mpy_cross) and ok
    except CheckError as err:
        print(f"firmware-check: {err}", file=sys.stderr)
        return 1
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
