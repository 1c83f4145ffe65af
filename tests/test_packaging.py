"""The installed distribution: import names and the console script."""

import os
import subprocess
import sys
import zipfile
from pathlib import Path

import pytest

import openbricks


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


@pytest.mark.e2e
def test_the_wheel_carries_everything_an_installed_openbricks_reads(tmp_path):
    """A pipx user gets no source checkout: the files the installed code opens must be in the wheel."""
    root = Path(__file__).resolve().parent.parent
    subprocess.run(
        [
            sys.executable,
            "-m",
            "pip",
            "wheel",
            "--no-deps",
            "--no-build-isolation",
            "-q",
            "-w",
            str(tmp_path),
            str(root),
        ],
        check=True,
        capture_output=True,
        timeout=600,
    )
    (wheel,) = tmp_path.glob("openbricks-*.whl")
    names = set(zipfile.ZipFile(wheel).namelist())
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
