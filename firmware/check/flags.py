"""The compiler command line of the esp32 port's build, for one target.

Taken from the build's own definitions wherever they can be read: ESP-IDF's default compile
options and definitions (build.cmake's __build_set_default_build_specifications), the
optimisation and assertion level from the target's sdkconfig, the esp32 port's warning
exceptions (esp32_common.cmake), and the include folders of include_path.py. What only the
Espressif toolchain would set is in toolchain_shim.h, included first.
"""

import re
from pathlib import Path

from steps import CheckError

CHECK_DIR = Path(__file__).resolve().parent
NATIVE = CHECK_DIR.parent / "native"
MODULE_DIR = NATIVE / "user_c_modules" / "openbricks"
TOOLCHAIN_SHIM = CHECK_DIR / "toolchain_shim.h"
# ESP-IDF's C library is newlib: its newlib component's platform headers wrap newlib's own
# (`#include_next <sys/reent.h>`), so the check compiles against newlib's headers (Debian's
# libnewlib-dev) rather than the cross compiler's default C library.
NEWLIB_INCLUDE = Path("/usr/include/newlib")
COMPILER = ["xtensa-lx106-elf-gcc"]
# ESP-IDF compiles every Xtensa file with long calls (its toolchain files); gcc's Xtensa port has it.
ARCH_FLAGS = ["-mlongcalls"]
OPTIMISATION = {
    "COMPILER_OPTIMIZATION_DEBUG": "-Og",
    "COMPILER_OPTIMIZATION_SIZE": "-Os",
    "COMPILER_OPTIMIZATION_PERF": "-O2",
    "COMPILER_OPTIMIZATION_NONE": "-O0",
}


def _quoted(block):
    return re.findall(r'"([^"]+)"', re.sub(r"#[^\n]*", "", block))


def idf_defaults(idf):
    """ESP-IDF's default (definitions, options, C options) for chip targets."""
    text = (idf / "tools" / "cmake" / "build.cmake").read_text()
    body = re.search(r"function\(__build_set_default_build_specifications\)(.*?)endfunction\(\)", text, re.S)
    if body is None:
        raise CheckError("ESP-IDF's build.cmake has no __build_set_default_build_specifications")
    body = body.group(1)

    def appended(name):
        return [
            v for block in re.findall(rf"list\(APPEND {name}\s(.*?)\)\n", body, re.S) for v in _quoted(block)
        ]

    return appended("compile_definitions"), appended("compile_options"), appended("c_compile_options")


def port_options(micropython):
    """The warning exceptions the esp32 port compiles MicroPython (and user C modules) with."""
    text = (micropython / "ports" / "esp32" / "esp32_common.cmake").read_text()
    block = re.search(r"target_compile_options\(\$\{MICROPY_TARGET\} PUBLIC(.*?)\)", text, re.S)
    if block is None:
        raise CheckError("esp32_common.cmake has no target_compile_options for MicroPython")
    return [word for word in block.group(1).split() if word.startswith("-W")]


def command_line(trees, target, config, includes, genhdr_root, board_dir):
    """(compiler, cpp_flags, c_flags) for one target."""
    definitions, options, c_options = idf_defaults(trees.idf)
    values = config.values
    level = [flag for name, flag in OPTIMISATION.items() if values.get(name)]
    if len(level) != 1:
        raise CheckError(f"the {target} sdkconfig sets {len(level)} optimisation levels")
    port = trees.micropython / "ports" / "esp32"
    defines = [f"-D{d}" for d in definitions] + [
        "-DESP_PLATFORM",
        '-DIDF_VER="v5.5.4"',
        "-DMICROPY_VFS_FAT=1",
        "-DMICROPY_VFS_LFS2=1",
        f'-DFFCONF_H="{trees.micropython / "lib" / "oofatfs" / "ffconf.h"}"',
    ]
    if values.get("COMPILER_OPTIMIZATION_ASSERTIONS_DISABLE"):
        defines.append("-DNDEBUG")
    include_dirs = [
        config.header_dir,  # sdkconfig.h
        genhdr_root,  # genhdr/
        trees.micropython,  # py/, shared/, extmod/ as "py/obj.h"...
        MODULE_DIR,
        NATIVE,
        port,
        board_dir,
        *includes,
    ]
    if not NEWLIB_INCLUDE.is_dir():
        raise CheckError(f"newlib's headers are not at {NEWLIB_INCLUDE}: install Debian's libnewlib-dev")
    cpp_flags = [
        "-include",
        str(TOOLCHAIN_SHIM),
        *defines,
        *[f"-I{d}" for d in include_dirs],
        "-isystem",
        str(NEWLIB_INCLUDE),
    ]
    c_flags = [*ARCH_FLAGS, *options, *c_options, level[0], *port_options(trees.micropython)]
    return COMPILER, cpp_flags, c_flags
