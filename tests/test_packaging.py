"""The installed distribution: import names, the console script, and the sdist and wheel a release ships.

The e2e tests build one release per test run, as `python -m build` builds it from a clean clone (the
console and the manual built by the build backend, not by `make`), then install the sdist the way a user
does, into a fresh venv on a PATH with no node, and use it: the commands, the console's pages, the manual.
"""

import importlib.util
import json
import os
import re
import shutil
import signal
import subprocess
import sys
import tarfile
import time
import zipfile
from dataclasses import dataclass
from html.parser import HTMLParser
from pathlib import Path
from urllib.parse import urljoin, urlsplit

import httpx
import pytest

import openbricks

ROOT = Path(__file__).resolve().parent.parent
BUILD_TIMEOUT_S = 900
INSTALL_TIMEOUT_S = 900
COMMAND_TIMEOUT_S = 120
CONSOLE_START_TIMEOUT_S = 60
HUBS_IDLE_TIMEOUT_S = 90
# A wheel or sdist far past this has swallowed something it should not carry (node_modules, a build dir).
MAX_ARCHIVE_BYTES = 10 * 1024 * 1024
NODE_TOOLS = {"node", "nodejs", "npm", "npx", "corepack"}
FIGURES = ROOT / "build" / "artifacts" / "packaging" / "figures.json"


def backend():
    """The in-tree build backend, imported as the build frontend imports it (from the root: backend-path)."""
    spec = importlib.util.spec_from_file_location(
        "build_backend", ROOT / "build_backend.py"
    )
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_console_script_reports_the_runtime_version():
    out = subprocess.run(
        [sys.executable, "-m", "openbricks_server.cli", "--version"],
        capture_output=True,
        text=True,
        check=True,
    )
    assert out.stdout.strip() == f"openbricks {openbricks.__version__}"


def test_host_packages_install_under_openbricks_names():
    import openbricks_native
    import openbricks_server
    import openbricks_sim

    for module in (openbricks_server, openbricks_sim, openbricks_native):
        assert module.__name__.startswith("openbricks")


def test_the_manuals_toolchain_is_asked_for_only_while_the_manual_is_absent(tmp_path):
    """A wheel built from the sdist (a user's install) must not download Sphinx and MuJoCo."""
    build = backend()
    shutil.copyfile(ROOT / "pyproject.toml", tmp_path / "pyproject.toml")
    wanted = {build._project_name(r) for r in build._extra_requirements(tmp_path)}
    assert {"sphinx", "myst-parser", "furo", "sphinx-argparse", "mujoco", "numpy"} <= wanted
    assert not wanted & {"viser", "distributed"}, "only what the manual's build imports"
    (tmp_path / "server" / "docs_html").mkdir(parents=True)
    (tmp_path / "server" / "docs_html" / "index.html").write_text("<html></html>")
    assert build._extra_requirements(tmp_path) == []


def test_a_console_that_needs_npm_without_it_names_npm(tmp_path, monkeypatch):
    build = backend()
    (tmp_path / "web").mkdir()
    shutil.copyfile(ROOT / "web" / "package-lock.json", tmp_path / "web" / "package-lock.json")
    monkeypatch.setenv("PATH", str(tmp_path / "empty-bin"))
    with pytest.raises(build.AssetBuildError, match=r"npm is not on PATH.*install Node\.js"):
        build.ensure_console(tmp_path)
    assert not (tmp_path / "web" / "node_modules").exists()


def test_a_manual_that_needs_sphinx_without_it_names_what_is_missing(tmp_path):
    build = backend()
    (tmp_path / "docs").mkdir()
    (tmp_path / "docs" / "conf.py").write_text("")
    (tmp_path / "pyproject.toml").write_text(
        '[project.optional-dependencies]\ndocs = ["sphinx>=8", "no-such-sphinx-theme>=1"]\nsim = ["numpy"]\n'
    )
    with pytest.raises(build.AssetBuildError, match=r"cannot build it: no .*no_such_sphinx_theme in "):
        build.ensure_manual(tmp_path)
    assert not (tmp_path / "server").exists()


# --- The release, built and installed as a user gets it (e2e) ---------------------------------------


@dataclass
class Release:
    sdist: Path
    wheel: Path
    build_s: float

    def sdist_names(self) -> set[str]:
        with tarfile.open(self.sdist) as archive:
            return {name.split("/", 1)[1] for name in archive.getnames() if "/" in name}

    def wheel_names(self) -> set[str]:
        with zipfile.ZipFile(self.wheel) as archive:
            return set(archive.namelist())


def clean_clone(target: Path) -> Path:
    """The working tree's files that git would commit (tracked and new, nothing ignored): a clean clone
    of what is being tested, with no console, manual or extension built by an earlier `make`."""
    listed = subprocess.run(
        ["git", "ls-files", "-z", "--cached", "--others", "--exclude-standard"],
        cwd=ROOT,
        capture_output=True,
        check=True,
        timeout=60,
    ).stdout.split(b"\0")
    for name in filter(None, (entry.decode() for entry in listed)):
        source = ROOT / name
        if source.is_file():  # a tracked file deleted in the working tree is not part of it
            (target / name).parent.mkdir(parents=True, exist_ok=True)
            shutil.copy2(source, target / name)
    for built in ("server/daemon/static", "server/docs_html", "web/node_modules"):
        assert not (target / built).exists(), built
    return target


def run_logged(command: list[str], log: Path, timeout: float, **kwargs) -> float:
    """Run to the end with its output in `log`; the seconds it took. A failure shows the log's tail."""
    started = time.monotonic()
    with log.open("w") as out:
        done = subprocess.run(command, stdout=out, stderr=subprocess.STDOUT, timeout=timeout, **kwargs)
    if done.returncode != 0:
        raise AssertionError(f"{' '.join(command)} exited {done.returncode}:\n{log.read_text()[-6000:]}")
    return time.monotonic() - started


@pytest.fixture(scope="session")
def release(tmp_path_factory) -> Release:
    """One sdist and one wheel for the whole test run, by `python -m build` on a clean clone (the sdist first,
    the wheel from it), on the developer's PATH: node and the Sphinx toolchain are the sdist's to use."""
    scratch = tmp_path_factory.mktemp("release")
    tree = clean_clone(scratch / "clone")
    dist = scratch / "dist"
    build_s = run_logged(
        [sys.executable, "-m", "build", "--outdir", str(dist), str(tree)],
        scratch / "build.log",
        BUILD_TIMEOUT_S,
        cwd=tree,
    )
    (sdist,) = dist.glob("openbricks-*.tar.gz")
    (wheel,) = dist.glob("openbricks-*.whl")
    return Release(sdist, wheel, build_s)


def record_figures(**figures) -> None:
    """The release's sizes and times, kept in build/artifacts for the run's record and printed."""
    FIGURES.parent.mkdir(parents=True, exist_ok=True)
    known = json.loads(FIGURES.read_text()) if FIGURES.is_file() else {}
    known.update(figures)
    FIGURES.write_text(json.dumps(known, indent=2) + "\n")
    print(f"packaging figures: {json.dumps(figures)}")


@pytest.mark.e2e
@pytest.mark.timeout(BUILD_TIMEOUT_S + 120)
def test_the_sdist_carries_the_built_pages_the_examples_and_the_c_sources(release):
    names = release.sdist_names()
    for page in (
        "server/daemon/static/index.html",
        "server/docs_html/index.html",
        "server/docs_html/cli.html",
    ):
        assert page in names, page
    assert any(n.startswith("server/daemon/static/assets/") and n.endswith(".js") for n in names)
    assert "server/keys/firmware_signing.pub" in names
    assert "build_backend.py" in names, "the backend the wheel is built with"
    examples = sorted(p.relative_to(ROOT).as_posix() for p in (ROOT / "examples").rglob("*.py"))
    assert examples and set(examples) <= names
    # The host extensions' C (setup.py); the wheel is built from this sdist, which proves nothing is missing.
    native = ROOT / "firmware" / "native"
    c_sources = [
        *native.glob("*.[ch]"),
        *(native / "bindings" / "cpython").glob("*.[ch]"),
        native / "platform" / "hard_timer_posix.c",
        *(native / "user_c_modules" / "openbricks_bench").glob("emulated_servo.[ch]"),
        *(ROOT / "sim" / "native").rglob("*.[ch]"),
    ]
    assert len(c_sources) > 30
    for path in c_sources:
        assert path.relative_to(ROOT).as_posix() in names, path
    assert not any("node_modules" in n or "__pycache__" in n for n in names)
    assert release.sdist.stat().st_size < MAX_ARCHIVE_BYTES


@pytest.mark.e2e
@pytest.mark.timeout(BUILD_TIMEOUT_S + 120)
def test_the_wheel_carries_everything_an_installed_openbricks_reads(release, tmp_path):
    """A pipx user gets no source checkout: the files the installed code opens must be in the wheel."""
    wheel = release.wheel
    names = release.wheel_names()
    site = "openbricks_server/docs_html/"
    for page in ("index.html", "api/drivebase.html", "cli-reference.html", "searchindex.js"):
        assert site + page in names, f"the documentation site of `openbricks docs` (`make docs`): {page}"
    assert any(n.startswith(site + "_static/") and n.endswith(".css") for n in names), "the site's theme"
    assert "openbricks_server/keys/firmware_signing.pub" in names, "flash's provenance check"
    assert "openbricks_server/flash/qtr_starter.json" in names, "flash --with-qtr-init"
    console = "openbricks_server/daemon/static/"
    assert console + "index.html" in names, "the browser console the daemon serves (`make web` builds it)"
    assert any(n.startswith(console + "assets/") and n.endswith(".js") for n in names), "the console's script"
    for extension in ("openbricks_native", "openbricks_mjcontrol", "openbricks_pycost"):
        assert any(n.startswith(extension) and n.endswith(".so") for n in names), extension
    assert not any("node_modules" in n for n in names)
    assert wheel.stat().st_size < MAX_ARCHIVE_BYTES

    # `openbricks docs` from those files alone, as a wheel install runs it: the page it opens is the
    # wheel's, a file:// page that loads nothing from the network (tests/docs checks every page).
    installed = tmp_path / "site-packages"
    zipfile.ZipFile(wheel).extractall(installed)
    record = tmp_path / "opened.txt"
    browser = tmp_path / "browser"
    browser.write_text(f'#!/bin/sh\necho "$1" >> "{record}"\n')
    browser.chmod(0o755)
    env = {**os.environ, "PYTHONPATH": str(installed), "BROWSER": f"{browser} %s"}
    env.pop("OPENBRICKS_DOCS_DIR", None)
    done = subprocess.run(
        [sys.executable, "-m", "openbricks_server.cli", "docs", "drivebase"],
        capture_output=True,
        text=True,
        env=env,
        cwd=tmp_path,
        timeout=60,
    )
    assert done.returncode == 0, done.stderr
    opened = Path(record.read_text().split()[0].removeprefix("file://"))
    assert opened == installed / site / "api" / "drivebase.html" and opened.is_file()


@pytest.mark.e2e
def test_a_build_that_needs_node_without_it_stops_with_one_line_naming_npm(tmp_path):
    """No package without its pages: a clean clone built where there is no npm produces nothing."""
    tree = clean_clone(tmp_path / "clone")
    env = {**os.environ, "PATH": path_without_node(tmp_path / "bin")}
    done = subprocess.run(
        [sys.executable, "-m", "build", "--sdist", "--no-isolation", "--skip-dependency-check"]
        + ["--outdir", str(tmp_path / "dist"), str(tree)],
        capture_output=True,
        text=True,
        env=env,
        timeout=COMMAND_TIMEOUT_S,
    )
    assert done.returncode != 0
    output = done.stdout + done.stderr
    assert "openbricks: cannot build the package: the browser console is not built" in output, output
    assert "npm is not on PATH" in output and "Traceback" not in output
    assert not list((tmp_path / "dist").glob("openbricks-*"))


def path_without_node(folder: Path) -> str:
    """A PATH with every program of this one but node's: the compiler pip builds the extensions with is
    there, node and npm are not (on Debian they share /usr/bin, so dropping a folder would not do)."""
    folder.mkdir()
    for directory in os.environ["PATH"].split(os.pathsep):
        if not os.path.isdir(directory):
            continue
        for entry in os.scandir(directory):
            if entry.name in NODE_TOOLS or (folder / entry.name).exists():
                continue
            if entry.is_file() and os.access(entry.path, os.X_OK):
                (folder / entry.name).symlink_to(entry.path)
    path = str(folder)
    assert all(shutil.which(tool, path=path) is None for tool in NODE_TOOLS)
    assert shutil.which("cc", path=path) or shutil.which("gcc", path=path), "a C compiler for the wheel"
    return path


class _References(HTMLParser):
    """The URLs a page loads or links: script src, link href, img src, a href."""

    def __init__(self):
        super().__init__()
        self.urls: list[str] = []

    def handle_starttag(self, tag, attrs):
        wanted = {"script": "src", "link": "href", "img": "src", "a": "href"}.get(tag)
        value = dict(attrs).get(wanted) if wanted else None
        if value:
            self.urls.append(value)


def local_references(page_url: str, html: str) -> set[str]:
    """The page's references that the console itself serves (no other host, no anchors, no mailto)."""
    parser = _References()
    parser.feed(html)
    found = set()
    for url in parser.urls:
        absolute = urlsplit(urljoin(page_url, url))
        if absolute.scheme in ("http", "https") and absolute.netloc == urlsplit(page_url).netloc:
            found.add(absolute.path)
    return found


def start_console(venv_bin: Path, env: dict, home: Path) -> tuple[subprocess.Popen, str, str, Path]:
    log = home / "console.log"
    with log.open("w") as out:
        process = subprocess.Popen(
            [
                str(venv_bin / "openbricks"),
                "console",
                "--no-ble",
                "--port",
                "0",
                "--data-dir",
                str(home / "c"),
            ],
            stdout=out,
            stderr=subprocess.STDOUT,
            env=env,
            cwd=home,
            start_new_session=True,  # its virtual hubs join its process group: one signal stops them all
        )
    deadline = time.monotonic() + CONSOLE_START_TIMEOUT_S
    while time.monotonic() < deadline:
        found = re.search(r"open (http://127\.0\.0\.1:\d+)/\?token=(\S+)", log.read_text())
        if found:
            return process, found.group(1), found.group(2), log
        if process.poll() is not None:
            break
        time.sleep(0.2)
    stop_console(process)
    raise AssertionError(f"the installed console printed no sign-in URL:\n{log.read_text()}")


def stop_console(process: subprocess.Popen) -> None:
    """Ctrl-C, as a user stops it (it stops its virtual hubs); the whole group killed if it lingers."""
    if process.poll() is None:
        process.send_signal(signal.SIGINT)
        try:
            process.wait(timeout=30)
        except subprocess.TimeoutExpired:
            process.kill()
            process.wait(timeout=10)
    try:
        os.killpg(process.pid, signal.SIGKILL)  # anything of the group that outlived it
    except ProcessLookupError:
        pass


@pytest.mark.e2e
@pytest.mark.timeout(BUILD_TIMEOUT_S + INSTALL_TIMEOUT_S + 300)
def test_the_sdist_installs_without_node_and_its_console_serves_the_pages_and_the_manual(release, tmp_path):
    home = tmp_path / "home"
    home.mkdir()
    no_node = path_without_node(tmp_path / "bin")
    venv = tmp_path / "venv"
    subprocess.run([sys.executable, "-m", "venv", str(venv)], check=True, timeout=120)
    venv_bin = venv / "bin"
    # pip as the machine has it set up (its index, its cache); only node is gone from the PATH.
    install_env = {k: v for k, v in os.environ.items() if k not in ("PYTHONPATH", "VIRTUAL_ENV")}
    install_env["PATH"] = os.pathsep.join((str(venv_bin), no_node))
    install_s = run_logged(
        [str(venv_bin / "python"), "-m", "pip", "install", f"{release.sdist}[sim]"],
        tmp_path / "install.log",
        INSTALL_TIMEOUT_S,
        env=install_env,
        cwd=home,
    )
    record_figures(
        sdist_bytes=release.sdist.stat().st_size,
        wheel_bytes=release.wheel.stat().st_size,
        build_s=round(release.build_s, 1),
        install_s=round(install_s, 1),
    )

    # From here on, the user: a home of their own, no checkout, nothing of the suite's environment.
    user_env = {
        k: v for k, v in install_env.items() if not k.startswith(("OPENBRICKS_", "XDG_", "PIP_", "BROWSER"))
    }
    user_env.update(HOME=str(home), OPENBRICKS_RUNTIME_DIR=str(home / "run"), PYTHONUNBUFFERED="1")

    def openbricks_cli(*args: str) -> str:
        done = subprocess.run(
            [str(venv_bin / "openbricks"), *args],
            capture_output=True,
            text=True,
            env=user_env,
            cwd=home,
            timeout=COMMAND_TIMEOUT_S,
        )
        assert done.returncode == 0, f"openbricks {' '.join(args)}: {done.stderr}"
        return done.stdout

    site_packages = next((venv / "lib").glob("python3*/site-packages"))
    assert openbricks_cli("--version").strip() == f"openbricks {openbricks.__version__}"

    with tarfile.open(release.sdist) as sdist:  # the example as the user has it: from the sdist
        member = next(m for m in sdist.getmembers() if m.name.endswith("/examples/drivebase_square.py"))
        (home / "drivebase_square.py").write_bytes(sdist.extractfile(member).read())
    result = json.loads(openbricks_cli("sim", "run", "drivebase_square.py", "--json").splitlines()[-1])
    assert result["exit"] == "finished", result
    assert "done" in result["output"]

    manual = Path(openbricks_cli("docs", "--path").strip())
    assert manual == site_packages / "openbricks_server" / "docs_html" / "index.html" and manual.is_file()

    console, base, token, log = start_console(venv_bin, user_env, home)
    try:
        with httpx.Client(base_url=base, follow_redirects=True, timeout=30) as browser:
            page = browser.get("/", params={"token": token})  # traded for the sign-in cookie
            assert page.status_code == 200 and "text/html" in page.headers["content-type"]
            references = local_references(f"{base}/", page.text)
            assert any(r.endswith(".js") for r in references) and any(r.endswith(".css") for r in references)
            # The chunks the page loads later (each page of the console) are the installed assets folder.
            assets = site_packages / "openbricks_server" / "daemon" / "static" / "assets"
            references |= {f"/assets/{p.name}" for p in assets.iterdir()}
            for reference in sorted(references):
                answer = browser.get(reference)
                assert answer.status_code == 200, f"{reference}: {answer.status_code}"
                assert answer.content, reference

            manual_page = browser.get("/manual/")
            assert manual_page.status_code == 200 and "openbricks" in manual_page.text
            manual_refs = local_references(f"{base}/manual/", manual_page.text)
            assert any(r.startswith("/manual/_static/") for r in manual_refs)
            for reference in sorted(manual_refs):
                assert browser.get(reference).status_code == 200, reference

            # Its virtual hubs are the installed simulator, in processes of their own.
            deadline = time.monotonic() + HUBS_IDLE_TIMEOUT_S
            hubs = []
            while time.monotonic() < deadline:
                hubs = browser.get("/api/hubs").json()["hubs"]
                if sum(h["status"] == "idle" for h in hubs) >= 2:
                    break
                time.sleep(0.5)
            assert sorted(h["name"] for h in hubs if h["status"] == "idle") == ["SimHub-1", "SimHub-2"], hubs
    finally:
        stop_console(console)
    assert console.returncode in (0, 130), log.read_text()
    assert "Traceback" not in log.read_text()
