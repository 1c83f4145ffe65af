"""Sphinx configuration of the openbricks user documentation (`make docs`).

The site is built into the host package (server/docs_html), so `openbricks docs` and the console serve it
offline from an installed wheel. The runtime's API pages are generated from its docstrings: autodoc
imports `openbricks.*` on CPython inside the simulator's shim, the same `machine`, `time` and
`_openbricks_native` a program gets in `openbricks sim run`. Screenshots come from the browser tests'
artefacts when a test run left them (build/artifacts), else from the copies committed in docs/screenshots.
"""

import shutil
from pathlib import Path

import openbricks

DOCS = Path(__file__).resolve().parent
ROOT = DOCS.parent

project = "openbricks"
author = "the openbricks contributors"
copyright = "the openbricks contributors, MIT licensed"
release = version = openbricks.__version__

extensions = [
    "myst_parser",
    "sphinx.ext.autodoc",
    "sphinxarg.ext",
]
myst_enable_extensions = ["colon_fence", "deflist"]
myst_heading_anchors = 3
source_suffix = {".md": "markdown"}
exclude_patterns = ["_build", "screenshots/README.md"]
# A page outside every toctree, an unknown reference or a missing listing is a build error under -W.
suppress_warnings: list[str] = []

highlight_language = "text"  # an unlabelled block is shown as typed; Python listings say so
html_theme = "furo"
html_title = f"openbricks {release}"
html_copy_source = False
html_show_sourcelink = False
html_static_path: list[str] = []
html_last_updated_fmt = None

# The runtime's docstrings quote names in single backticks, as Markdown does: show them as code.
default_role = "literal"
autodoc_member_order = "bysource"
autodoc_default_options = {"members": True, "show-inheritance": True}
autoclass_content = "both"
# The hub runtime has no annotations (MicroPython); signatures come from the code.
autodoc_typehints = "none"

SCREENSHOTS = (
    "dashboard",
    "output-two-hubs",
    "history-run",
    "dashboard-viewer",
    "telemetry-live",
    "viewer-3d",
)
ARTEFACT_DIRS = (ROOT / "build" / "artifacts" / "web", ROOT / "build" / "artifacts" / "sim")


def _collect_screenshots():
    """docs/_screenshots/NAME.png: the browser tests' latest picture, or the committed one."""
    target = DOCS / "_screenshots"
    target.mkdir(exist_ok=True)
    for name in SCREENSHOTS:
        fresh = [d / f"{name}.png" for d in ARTEFACT_DIRS if (d / f"{name}.png").is_file()]
        source = fresh[0] if fresh else DOCS / "screenshots" / f"{name}.png"
        if source.is_file():
            shutil.copyfile(source, target / f"{name}.png")


def _install_simulated_hub():
    """autodoc imports the runtime as a program does in the simulator: machine, time, esp32... are the
    shim's, bound to a simulated hub in an empty world."""
    from openbricks_sim.shim import Shim
    from openbricks_sim.simulation import Simulation

    Shim(Simulation(world="empty")).install()


def setup(app):
    _collect_screenshots()
    _install_simulated_hub()
