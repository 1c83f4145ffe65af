"""Where the ESP-IDF and MicroPython esp32 sources come from, unpacked once under the build folder.

The check compiles against the real headers of the versions the firmware targets: ESP-IDF v5.5.4
and MicroPython v1.28.0's esp32 port, as source archives (by default the ones in the `shared/esp32/`
folder beside this checkout, or beside the main checkout of a git worktree) or trees of your own
(`--idf`, `--micropython`: a folder or a `.tar.gz`).
"""

import shutil
import subprocess
import tarfile
from dataclasses import dataclass
from pathlib import Path

from steps import CheckError

REPO = Path(__file__).resolve().parents[2]
IDF_ARCHIVE = "esp-idf-v5.5.4-esp32-src.tar.gz"
MICROPYTHON_ARCHIVE = "micropython-1.28.0-esp32-src.tar.gz"

# Files the ESP-IDF archive leaves out (other chips' folders) that a Kconfig file of ours still
# sources, with what their absence costs. Each is written as an empty file into the unpacked copy,
# and the check prints the list, so a gap is never silent. Anything else missing is an error.
ARCHIVE_GAPS = {
    "components/bt/controller/esp32c3/Kconfig.in": (
        "the ESP32-S3's BLE controller options (ESP-IDF shares them with the C3's folder, which the "
        "archive leaves out); none is set by the boards' fragments"
    ),
}


@dataclass(frozen=True)
class Trees:
    idf: Path
    micropython: Path


def _shared_folder():
    """The `shared/esp32` folder beside this checkout (or beside the main checkout of a worktree)."""
    candidates = [REPO.parent / "shared" / "esp32"]
    try:
        common = subprocess.run(
            ["git", "-C", str(REPO), "rev-parse", "--path-format=absolute", "--git-common-dir"],
            capture_output=True,
            text=True,
            timeout=10,
            check=True,
        ).stdout.strip()
        candidates.append(Path(common).parent.parent / "shared" / "esp32")
    except (OSError, subprocess.SubprocessError):
        pass
    for folder in candidates:
        if folder.is_dir():
            return folder
    return candidates[0]


def _tree(source, marker, into):
    """The source tree `source` names (a folder, or a tarball unpacked once into `into`)."""
    source = Path(source).expanduser().resolve()
    if source.is_dir():
        if not (source / marker).exists():
            raise CheckError(f"{source} does not look like the tree it should be (no {marker})")
        return source
    if not source.is_file():
        raise CheckError(
            f"source archive {source} not found: put it there, or give a tree or archive of your own "
            "with --idf / --micropython"
        )
    stamp = into / (source.name + ".unpacked")
    if not stamp.is_file():
        shutil.rmtree(into, ignore_errors=True)
        into.mkdir(parents=True)
        try:
            with tarfile.open(source) as archive:
                archive.extractall(into, filter="data")
        except (tarfile.TarError, OSError) as err:
            raise CheckError(f"could not unpack {source}: {err}") from None
        stamp.touch()
    trees = [p for p in into.iterdir() if (p / marker).exists()]
    if len(trees) != 1:
        raise CheckError(f"{source} does not hold one source tree with {marker} (found {len(trees)})")
    return trees[0]


def trees(build, idf=None, micropython=None):
    """Both source trees, unpacked under `build` when they are archives, with the known gaps filled."""
    shared = _shared_folder()
    idf_tree = _tree(idf or shared / IDF_ARCHIVE, "components/esp_timer", build / "esp-idf")
    mp_tree = _tree(
        micropython or shared / MICROPYTHON_ARCHIVE, "ports/esp32/mpconfigport.h", build / "micropython"
    )
    for gap in ARCHIVE_GAPS:
        path = idf_tree / gap
        if not path.exists() and path.parent.parent.is_dir():
            path.parent.mkdir(parents=True, exist_ok=True)
            path.write_text("# Left out of the source archive; see firmware/check/sources.py.\n")
    return Trees(idf_tree, mp_tree)
