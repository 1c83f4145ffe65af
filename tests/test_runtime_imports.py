"""What the hub runtime may import, checked from the source (no interpreter needed).

`openbricks/` and the frozen boot.py / main.py (firmware/frozen/) go into a
MicroPython image for the ESP32: they can import only what that image has,
and nothing of the host. The MicroPython run
(tests/micropython) proves each module imports on the WebAssembly port, but
that port carries extras the hub lacks (functools, logging, inspect, ...), so
the allowlist is the hub's own list (openbricks_sim/hub_modules.py, which the
simulator also holds programs to): MicroPython's ESP32 port as firmware/ builds it.
"""

import ast
from pathlib import Path

import pytest

from openbricks_sim.hub_modules import HUB_MODULES, REFUSED

REPO = Path(__file__).resolve().parents[1]
RUNTIME_DIR = REPO / "openbricks"
FROZEN_DIR = REPO / "firmware" / "frozen"

HOST_LAYERS = ("openbricks_server", "openbricks_sim")


def _runtime_files():
    return sorted(p for p in RUNTIME_DIR.rglob("*.py") if "__pycache__" not in p.parts)


def _image_files():
    """Everything frozen into the image: the runtime, and the boot.py / main.py that start it."""
    return _runtime_files() + sorted(FROZEN_DIR.glob("*.py"))


def _imports(path):
    """(line, imported module as written) for every import in the file, nested ones included.

    Relative imports are inside openbricks by construction and come back as "openbricks"; an
    `__import__("name")` with a literal name counts as an import of that name.
    """
    tree = ast.parse(path.read_text(encoding="utf-8"), filename=str(path))
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            for alias in node.names:
                yield node.lineno, alias.name
        elif isinstance(node, ast.ImportFrom):
            yield node.lineno, "openbricks" if node.level else node.module
        elif (
            isinstance(node, ast.Call)
            and isinstance(node.func, ast.Name)
            and node.func.id == "__import__"
            and node.args
            and isinstance(node.args[0], ast.Constant)
            and isinstance(node.args[0].value, str)
        ):
            yield node.lineno, node.args[0].value


def _fail_listing(problems):
    if problems:
        pytest.fail("\n".join(problems), pytrace=False)


def _where(path, line):
    return f"{path.relative_to(REPO).as_posix()}:{line}"


def _not_on_the_hub(name):
    """Why `name` cannot be imported by the runtime, or None when it can."""
    top = name.split(".")[0]
    if top == "openbricks" or top in HUB_MODULES:
        return None
    if top in REFUSED:
        return REFUSED[top]
    if top.startswith("u") and top[1:] in HUB_MODULES:
        plain = top[1:]
        return (
            f"import `{plain}`: the u-prefixed alias is deprecated, and the test fakes replace only `{plain}`"
        )
    return "MicroPython's ESP32 port does not have it"


def test_the_runtime_imports_only_what_the_hub_has():
    problems = []
    for path in _image_files():
        for line, name in _imports(path):
            why = _not_on_the_hub(name)
            if why is not None:
                problems.append(f"{_where(path, line)}: import {name} is not available on the hub ({why})")
    _fail_listing(problems)


def test_the_runtime_never_imports_the_host_layers():
    problems = []
    for path in _image_files():
        for line, name in _imports(path):
            if name.split(".")[0] in HOST_LAYERS:
                problems.append(
                    f"{_where(path, line)}: import {name}: the hub runtime imports nothing of the host "
                    "(layers run server -> sim -> openbricks, never back)"
                )
    _fail_listing(problems)


def _module_level_statements(tree):
    """Statements that run at import: the module body and the blocks of its if/try/with."""
    pending = list(tree.body)
    while pending:
        node = pending.pop()
        yield node
        if isinstance(node, ast.If | ast.Try | ast.With):
            pending.extend(node.body)
            pending.extend(getattr(node, "orelse", []))
            pending.extend(getattr(node, "finalbody", []))
            for handler in getattr(node, "handlers", []):
                pending.extend(handler.body)


def _module_level_native_imports(path):
    """Lines where `_openbricks_native` is imported at import time of the module."""
    tree = ast.parse(path.read_text(encoding="utf-8"), filename=str(path))
    lines = []
    for node in _module_level_statements(tree):
        if isinstance(node, ast.Import):
            names = [alias.name for alias in node.names]
        elif isinstance(node, ast.ImportFrom) and not node.level:
            names = [node.module]
        else:
            continue
        if "_openbricks_native" in names:
            lines.append(node.lineno)
    return sorted(lines)


def test_the_native_cores_are_imported_lazily():
    """A build without the cores (the WebAssembly MicroPython, a bare firmware) must still import
    every module, so `_openbricks_native` is imported inside the function that needs it."""
    problems = [
        f"{_where(path, line)}: _openbricks_native is imported at module level; "
        "import it inside the constructor or function that needs it"
        for path in _runtime_files()
        for line in _module_level_native_imports(path)
    ]
    _fail_listing(problems)


# The checks above must catch what they claim to: run them on small sources.


def _problems_in(tmp_path, source, check):
    path = tmp_path / "openbricks" / "probe.py"
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(source, encoding="utf-8")
    return [(line, name, check(name)) for line, name in _imports(path)]


def test_the_allowlist_check_names_the_line_and_the_reason(tmp_path):
    source = (
        "import time\n"
        "from machine import Pin\n"
        "from . import pins\n"
        "def f():\n"
        "    import functools\n"
        "    import network\n"
        "    import utime\n"
        "    return __import__('typing')\n"
    )
    refused = {
        (line, name): why for line, name, why in _problems_in(tmp_path, source, _not_on_the_hub) if why
    }
    assert set(refused) == {(5, "functools"), (6, "network"), (7, "utime"), (8, "typing")}
    assert "WiFi is off" in refused[(6, "network")]
    assert "`time`" in refused[(7, "utime")]


def test_a_module_level_native_import_is_caught_but_a_lazy_one_is_not(tmp_path):
    probe = tmp_path / "probe.py"
    probe.write_text(
        "try:\n    import _openbricks_native\nexcept ImportError:\n    pass\n"
        "def tick():\n    import _openbricks_native\n"
        "class Drive:\n    def __init__(self):\n        from _openbricks_native import drivebase\n"
        "if True:\n    from _openbricks_native import scs\n",
        encoding="utf-8",
    )
    assert _module_level_native_imports(probe) == [2, 11]
