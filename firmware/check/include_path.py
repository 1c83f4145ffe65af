"""The include folders a file of the esp32 port's build sees, taken from ESP-IDF's own components.

The port registers MicroPython as one ESP-IDF component that REQUIRES a list of components
(`IDF_COMPONENTS` in esp32_common.cmake); ESP-IDF adds its common requirements and the target's
architecture component. A user C module is compiled as part of that component, so it sees the
public include folders of all of those and of everything they publicly require, transitively. This
module computes exactly that set by running each component's CMakeLists.txt in CMake's script mode
(components.cmake) against the target's sdkconfig.cmake, so target folders and `if(CONFIG_...)`
choices come out as ESP-IDF's build makes them.
"""

import re
from pathlib import Path

from steps import CheckError, run

COMPONENTS_SCRIPT = Path(__file__).resolve().parent / "components.cmake"
CMAKE_LIMIT_S = 60


def port_components(micropython):
    """The components the esp32 port's MicroPython component REQUIRES (its IDF_COMPONENTS lists)."""
    text = (micropython / "ports" / "esp32" / "esp32_common.cmake").read_text()
    names = []
    for block in re.findall(r"list\(\s*APPEND\s+IDF_COMPONENTS\b(.*?)\)", text, re.S):
        names += [word for word in block.split() if not word.startswith("#")]
    if not names:
        raise CheckError("esp32_common.cmake lists no IDF_COMPONENTS: is this MicroPython's esp32 port?")
    return names


def common_requirements(idf):
    """The components ESP-IDF makes every component require on a chip target (build.cmake)."""
    text = (idf / "tools" / "cmake" / "build.cmake").read_text()
    for group in re.findall(r"set\(\s*requires_common\s+([^)]*)\)", text):
        names = group.split()
        if "linux" not in names:
            return names
    raise CheckError("ESP-IDF's build.cmake sets no requires_common for chip targets")


def _read(idf, target, sdkconfig_cmake, names, out):
    listing = out / "components.txt"
    command = [
        "cmake",
        f"-DIDF_PATH={idf}",
        f"-DIDF_TARGET={target}",
        f"-DSDKCONFIG_CMAKE={sdkconfig_cmake}",
        f"-DCOMPONENTS={';'.join(names)}",
        f"-DOUTPUT={listing}",
        "-P",
        str(COMPONENTS_SCRIPT),
    ]
    run(command, f"reading ESP-IDF's components {', '.join(names)} (cmake -P)", CMAKE_LIMIT_S, cwd=out)
    found = {}
    for line in listing.read_text().splitlines():
        name, dirs, requires = line.split("|")
        found[name] = ([Path(d) for d in dirs.split(";") if d], [r for r in requires.split(";") if r])
    return found


def component_includes(trees, target, config, out, arch="xtensa"):
    """Public include folders of the port's components and their public requirements, in a stable order."""
    idf = trees.idf
    wanted = port_components(trees.micropython) + common_requirements(idf) + [arch]
    seen = {}
    pending = list(dict.fromkeys(wanted))
    while pending:
        batch = list(dict.fromkeys(name for name in pending if name not in seen))
        pending = []
        missing = [name for name in batch if not (idf / "components" / name).is_dir()]
        if missing:
            raise CheckError(f"ESP-IDF at {idf} has no component {', '.join(missing)}")
        if not batch:
            break
        for name, (dirs, requires) in _read(idf, target, config.cmake, batch, out).items():
            seen[name] = dirs
            pending += [r for r in requires if r not in seen]
        for name in batch:
            seen.setdefault(name, [])
    folders = []
    for name in sorted(seen):
        folders += [d for d in seen[name] if d.is_dir() and d not in folders]
    return folders
