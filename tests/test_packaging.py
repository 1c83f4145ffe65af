"""The installed distribution: import names and the console script."""

import subprocess
import sys

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
