"""The PEP 517 backend: setuptools' own, plus the two built assets an installed openbricks reads.

The console's pages (web/, built by npm into server/daemon/static) and the manual (docs/, built by
Sphinx into server/docs_html) are build outputs, not sources, so a clean clone has neither. A pip user
gets no checkout and must need neither node nor Sphinx, so the sdist carries both built: building the
sdist (`python -m build` does that first) runs `npm ci && npm run build` and the Sphinx build when their
outputs are absent, and the wheel built from that sdist finds them present and needs neither toolchain.
A wheel built straight from a checkout goes through the same step.

The Sphinx build needs the docs toolchain and, because the API pages import the runtime inside the
simulator's shim, MuJoCo and NumPy: they are asked for as build requirements only while the manual is
absent, so a wheel built from the sdist (a user's install) does not download them.

A build that would need the pages and cannot make them stops with the reason: a package without the
console or the manual is never produced. An archive is also opened after it is written and refused if
either site is missing from it, so a packaging rule that stops matching cannot ship one either.

Editable installs (`make setup`, `make console`) pass straight through: they read the source tree, where
`make web` and `make docs` build the pages.
"""

from __future__ import annotations

import importlib.util
import os
import shutil
import subprocess
import sys
import tarfile
import tempfile
import tomllib
import warnings
import zipfile
from pathlib import Path

from setuptools import build_meta as _setuptools
from setuptools.build_meta import (  # noqa: F401 - re-exported: the hooks this backend leaves as they are
    get_requires_for_build_editable,
    prepare_metadata_for_build_editable,
    prepare_metadata_for_build_wheel,
)

STATIC = Path("server/daemon/static")
MANUAL = Path("server/docs_html")
# What must be inside each archive, relative to its root (the sdist's top folder, the wheel's root).
SDIST_REQUIRED = (STATIC / "index.html", MANUAL / "index.html")
WHEEL_REQUIRED = (
    Path("openbricks_server/daemon/static/index.html"),
    Path("openbricks_server/docs_html/index.html"),
)
# The sim extra's requirements the manual's build imports (the shim's simulated hub), by project name;
# their versions are the ones pyproject.toml gives.
SIM_FOR_MANUAL = ("mujoco", "numpy", "pillow")
# The import name of each requirement, to say which are missing where isolation is off.
IMPORT_NAMES = {
    "sphinx": "sphinx",
    "myst-parser": "myst_parser",
    "furo": "furo",
    "sphinx-argparse": "sphinxarg",
    "mujoco": "mujoco",
    "numpy": "numpy",
    "pillow": "PIL",
}


class AssetBuildError(Exception):
    """A built asset the package must carry is absent and cannot be built here."""


def _root() -> Path:
    # PEP 517 runs every hook from the root of the source tree (a checkout or an unpacked sdist).
    return Path.cwd()


def _project_name(requirement: str) -> str:
    name = requirement
    for stop in "<>=!~[; ":
        name = name.split(stop, 1)[0]
    return name.strip().lower().replace("_", "-")


def manual_requirements(root: Path) -> list[str]:
    """The docs extra and the simulator packages the manual's build imports, as pyproject.toml pins them."""
    extras = tomllib.loads((root / "pyproject.toml").read_text())["project"]["optional-dependencies"]
    sim = [r for r in extras["sim"] if _project_name(r) in SIM_FOR_MANUAL]
    return [*extras["docs"], *sim]


def _extra_requirements(root: Path) -> list[str]:
    return [] if (root / MANUAL / "index.html").is_file() else manual_requirements(root)


def get_requires_for_build_sdist(config_settings=None):
    return _setuptools.get_requires_for_build_sdist(config_settings) + _extra_requirements(_root())


def get_requires_for_build_wheel(config_settings=None):
    return _setuptools.get_requires_for_build_wheel(config_settings) + _extra_requirements(_root())


def _run(command: list[str], cwd: Path, what: str, env: dict[str, str] | None = None) -> None:
    """Run one step with its output on the build's log; a failure names the step and the command."""
    print(f"openbricks: {what}: {' '.join(command)}", file=sys.stderr, flush=True)
    # The step's output goes to stderr: a frontend shows it, and stdout stays the frontend's channel.
    done = subprocess.run(command, cwd=cwd, env=env, stdout=sys.stderr, stderr=sys.stderr)
    if done.returncode != 0:
        raise AssetBuildError(
            f"{what} failed (exit {done.returncode}): {' '.join(command)}; its output is above"
        )


def ensure_console(root: Path) -> None:
    """server/daemon/static from web/ with npm, unless it is built already."""
    if (root / STATIC / "index.html").is_file():
        return
    web = root / "web"
    if not (web / "package-lock.json").is_file():
        raise AssetBuildError(
            f"the browser console is not built ({STATIC / 'index.html'} is absent) and its sources "
            "(web/package-lock.json) are not here to build it from"
        )
    npm = shutil.which("npm")
    if npm is None:
        raise AssetBuildError(
            f"the browser console is not built ({STATIC / 'index.html'} is absent) and npm is not on PATH "
            "to build it: install Node.js 20 (with npm), or `make web` first; a release sdist carries the "
            "built console and needs no node"
        )
    stamp = web / "node_modules" / ".installed"  # the Makefile's: `npm ci` once per lock file
    if not stamp.is_file() or stamp.stat().st_mtime < (web / "package-lock.json").stat().st_mtime:
        install = [npm, "ci", "--no-audit", "--no-fund", "--loglevel=error"]
        _run(install, web, "installing the console's npm packages")
        stamp.touch()
    _run([npm, "run", "build", "--silent"], web, "building the browser console")
    if not (root / STATIC / "index.html").is_file():
        raise AssetBuildError(f"`npm run build` in web/ succeeded but wrote no {STATIC / 'index.html'}")


def _missing_modules(requirements: list[str]) -> list[str]:
    names = [IMPORT_NAMES.get(_project_name(r), _project_name(r).replace("-", "_")) for r in requirements]
    return [name for name in names if importlib.util.find_spec(name) is None]


def ensure_manual(root: Path) -> None:
    """server/docs_html from docs/ with Sphinx, unless it is built already.

    As `make docs` does, with warnings as errors; the packages and extensions are built into a private
    folder that Sphinx imports them from (the source folders server/ and sim/ are not importable under
    their package names), and the site is moved into place only once it is whole."""
    if (root / MANUAL / "index.html").is_file():
        return
    if not (root / "docs" / "conf.py").is_file():
        raise AssetBuildError(
            f"the manual is not built ({MANUAL / 'index.html'} is absent) and its sources (docs/) "
            "are not here to build it from"
        )
    missing = _missing_modules(manual_requirements(root))
    if missing:
        raise AssetBuildError(
            f"the manual is not built ({MANUAL / 'index.html'} is absent) and this Python cannot build it: "
            f"no {', '.join(missing)} in {sys.executable}. Build with isolation (`python -m build` asks for "
            "them), install them (`pip install -e '.[docs,sim]'`), or `make docs` first"
        )
    with tempfile.TemporaryDirectory(prefix="openbricks-manual-") as scratch:
        lib = Path(scratch) / "lib"
        _run(
            [
                sys.executable, "setup.py", "-q",
                "build_py", "--build-lib", str(lib),
                "build_ext", "--build-lib", str(lib), "--build-temp", str(Path(scratch) / "temp"),
            ],
            root,
            "building the packages and extensions the manual's API pages import",
        )  # fmt: skip
        env = dict(os.environ)
        env["PYTHONPATH"] = os.pathsep.join(p for p in (str(lib), env.get("PYTHONPATH", "")) if p)
        env.pop("OPENBRICKS_DOCS_DIR", None)
        html = Path(scratch) / "html"
        _run(
            [
                sys.executable, "-m", "sphinx", "-W", "--keep-going", "-q", "-b", "html",
                "-d", str(Path(scratch) / "doctrees"), "docs", str(html),
            ],
            root,
            "building the manual",
            env=env,
        )  # fmt: skip
        if not (html / "index.html").is_file():
            raise AssetBuildError("Sphinx succeeded but wrote no index.html")
        shutil.rmtree(root / MANUAL, ignore_errors=True)
        shutil.move(html, root / MANUAL)


def ensure_assets(root: Path) -> None:
    ensure_console(root)
    ensure_manual(root)


def _check_archive(path: Path, names: set[str], required: tuple[Path, ...]) -> None:
    absent = [p.as_posix() for p in required if p.as_posix() not in names]
    if absent:
        path.unlink()
        raise AssetBuildError(
            f"{path.name} was built without {', '.join(absent)}; it was deleted. The package-data globs in "
            "pyproject.toml or MANIFEST.in no longer match the built pages"
        )


def _sdist_names(path: Path) -> set[str]:
    with tarfile.open(path) as archive:
        # Each member sits under the sdist's own top folder (openbricks-VERSION/).
        return {name.split("/", 1)[1] for name in archive.getnames() if "/" in name}


def _wheel_names(path: Path) -> set[str]:
    with zipfile.ZipFile(path) as archive:
        return set(archive.namelist())


def _exit_on_asset_error(hook):
    """A missing toolchain ends the build with one plain line, not a backend traceback."""

    def run(*args, **kwargs):
        try:
            return hook(*args, **kwargs)
        except AssetBuildError as exc:
            sys.exit(f"openbricks: cannot build the package: {exc}")

    run.__name__ = hook.__name__
    run.__doc__ = hook.__doc__
    return run


@_exit_on_asset_error
def build_sdist(sdist_directory, config_settings=None):
    ensure_assets(_root())
    name = _setuptools.build_sdist(sdist_directory, config_settings)
    path = Path(sdist_directory) / name
    _check_archive(path, _sdist_names(path), SDIST_REQUIRED)
    return name


@_exit_on_asset_error
def build_wheel(wheel_directory, config_settings=None, metadata_directory=None):
    ensure_assets(_root())
    name = _setuptools.build_wheel(wheel_directory, config_settings, metadata_directory)
    path = Path(wheel_directory) / name
    _check_archive(path, _wheel_names(path), WHEEL_REQUIRED)
    return name


def build_editable(wheel_directory, config_settings=None, metadata_directory=None):
    """setuptools' editable build, without its notice that an editable install of a package whose folder
    is named otherwise (server/ is openbricks_server) goes through an import finder: true of every
    install of this tree, it would only add a dozen lines of banner to every `make console`."""
    from setuptools.warnings import InformationOnly

    with warnings.catch_warnings():
        warnings.filterwarnings("ignore", message=r"\s*Editable installation\.", category=InformationOnly)
        return _setuptools.build_editable(wheel_directory, config_settings, metadata_directory)
