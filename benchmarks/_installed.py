"""This checkout as a user's install runs it, for whole-process figures beside the reference's.

The development venv imports the project through setuptools' editable finder, which every Python
process there pays for at start-up (about 20 ms: it imports pathlib and friends from `site`), and
which no user's install has. A wheel puts the packages on sys.path instead, byte-compiled. So the
figures that include start-up come from a throwaway venv laid out that way: the packages of this
checkout (linked, so what is measured is what is checked out) and the dependencies of the
development venv are plain sys.path entries (a .pth file), the sources byte-compiled, and an
`openbricks` console script as pip writes one. (The leading underscore keeps the benchmark runner
from taking this helper for a benchmark.)
"""

from __future__ import annotations

import compileall
import os
import site
import sys
import venv
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
PACKAGES = {"openbricks": "openbricks", "openbricks_sim": "sim", "openbricks_server": "server"}
EXTENSIONS = ("openbricks_native", "openbricks_mjcontrol", "openbricks_pycost")
SCRIPT = (  # what pip writes for pyproject.toml's [project.scripts] entry
    "#!{python}\nimport sys\nfrom openbricks_server.cli import run\n"
    "if __name__ == '__main__':\n    sys.exit(run())\n"
)


def venv_dir() -> Path:
    from openbricks_server.paths import cache_dir

    return cache_dir() / "bench-installed"


def openbricks() -> Path:
    """The `openbricks` console script of the installed layout, (re)made on each call (cheap)."""
    root = venv_dir()
    python = root / "bin" / "python"
    if not python.exists():
        venv.EnvBuilder(with_pip=False, symlinks=True).create(root)
    packages = root / "packages"
    packages.mkdir(exist_ok=True)
    for name, folder in PACKAGES.items():
        _link(packages / name, ROOT / folder)
    for module in EXTENSIONS:
        built = __import__(module).__file__
        _link(packages / os.path.basename(built), Path(built))
    site_packages = Path(
        next(p for p in Path(root, "lib").glob("python3*/site-packages"))  # the venv's own
    )
    # Ours first, then the development venv's dependencies (MuJoCo, numpy, ...), as plain entries.
    (site_packages / "openbricks-installed.pth").write_text(
        f"{packages}\n" + "".join(f"{p}\n" for p in site.getsitepackages()), encoding="utf-8"
    )
    for folder in PACKAGES.values():
        compileall.compile_dir(str(ROOT / folder), quiet=1)
    script = root / "bin" / "openbricks"
    script.write_text(SCRIPT.format(python=python), encoding="utf-8")
    script.chmod(0o755)
    return script


def _link(link: Path, target: Path) -> None:
    if link.is_symlink() and Path(os.readlink(link)) == target:
        return
    if link.is_symlink() or link.exists():
        link.unlink()
    link.symlink_to(target)


if __name__ == "__main__":
    print(openbricks())
    sys.exit(0)
