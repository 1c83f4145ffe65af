"""Every control core compiles as strict, warning-free C99, for the host and for a
32-bit target.

The cores are shared with the ESP32 firmware, whose toolchain is not on this
machine: a 32-bit build stands in for it (32-bit int, long and pointers, where
size_t/int mix-ups and missing casts show up). Cores are discovered by glob, so
a new core is checked the moment it lands. A machine that cannot build 32-bit
objects fails here rather than skipping: install gcc-multilib (`make setup` does).
"""

import shutil
import subprocess
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[3]
NATIVE = REPO / "firmware" / "native"
STRICT = ["-std=c99", "-Wall", "-Wextra", "-Werror", "-pedantic", "-O2"]
TARGETS = {"host": [], "m32": ["-m32"]}

CORES = sorted(NATIVE.glob("*.c"))
HEADERS = sorted(NATIVE.glob("*.h"))


def gcc():
    path = shutil.which("gcc")
    assert path, "gcc not found: the strict C99 build of firmware/native needs it (apt-get install gcc)"
    return path


def compile_c(args, source_text=None, cwd=None):
    return subprocess.run(
        [gcc(), *args], input=source_text, capture_output=True, text=True, cwd=cwd, timeout=120
    )


def test_the_cores_are_found():
    names = {path.name for path in CORES}
    assert {"scs.c", "imu_yaw.c"} <= names, f"expected the cores in {NATIVE}, found {sorted(names)}"


@pytest.mark.parametrize("target", TARGETS)
def test_the_compiler_builds_for_the_target(target, tmp_path):
    """The libc headers the cores use are present for the target (32-bit ones come with gcc-multilib)."""
    program = "#include <math.h>\n#include <stdint.h>\n#include <string.h>\nint main(void) { return 0; }\n"
    result = compile_c([*STRICT, *TARGETS[target], "-x", "c", "-", "-o", str(tmp_path / "probe")], program)
    hint = " Install gcc-multilib (`make setup` installs it)." if target == "m32" else ""
    assert result.returncode == 0, f"gcc cannot build {target} programs.{hint}\n{result.stderr}"


@pytest.mark.parametrize("target", TARGETS)
@pytest.mark.parametrize("source", CORES, ids=lambda path: path.name)
def test_core_compiles_warning_free(source, target, tmp_path):
    result = compile_c([*STRICT, *TARGETS[target], "-c", str(source), "-o", str(tmp_path / "core.o")])
    assert result.returncode == 0, (
        f"{source.relative_to(REPO)} fails the strict C99 build ({target}: "
        f"gcc {' '.join(STRICT + TARGETS[target])}):\n{result.stderr}"
    )


@pytest.mark.parametrize("header", HEADERS, ids=lambda path: path.name)
def test_header_stands_on_its_own(header, tmp_path):
    """Each header includes what it uses, so the firmware may include them in any order."""
    unit = f'#include "{header.name}"\n'
    result = compile_c([*STRICT, f"-I{NATIVE}", "-x", "c", "-fsyntax-only", "-"], unit, cwd=tmp_path)
    assert result.returncode == 0, f"{header.relative_to(REPO)} does not compile on its own:\n{result.stderr}"
