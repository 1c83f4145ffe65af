"""The hub runtime's tests, run a second time under the real MicroPython interpreter.

Collection finds, from the source alone, every runtime test function
(tests/openbricks/**/test_*.py, minus files that set NEEDS_NATIVE = True) and
every module under openbricks/, and makes one pytest test of each:
`mpy::drivers/test_l298n.py::test_invert_swaps_the_direction`, `import::openbricks.drivers.st3215`.
One run of run_tests.mjs (the WebAssembly MicroPython in Node) produces all
their results; each test then reports its own, with MicroPython's traceback.
The pytest summary therefore counts the CPython runs and the MicroPython runs.
"""

import ast
import json
import shutil
import subprocess
from pathlib import Path

import pytest

HERE = Path(__file__).resolve().parent
REPO = HERE.parents[1]
RUNTIME_DIR = REPO / "openbricks"
RUNTIME_TESTS_DIR = REPO / "tests" / "openbricks"
RUNNER = HERE / "run_tests.mjs"
INTERPRETER_PACKAGE = HERE / "node_modules" / "@micropython" / "micropython-webassembly-pyscript"

# Inside pytest-timeout's 300 s per test (the run happens in the first test's setup).
RUN_LIMIT_S = 240
STEP_LIMIT_S = 30

pytestmark = pytest.mark.micropython


def _module_name(path):
    parts = list(path.relative_to(REPO).with_suffix("").parts)
    if parts[-1] == "__init__":
        parts.pop()
    return ".".join(parts)


def _runtime_modules():
    return sorted(_module_name(p) for p in RUNTIME_DIR.rglob("*.py") if "__pycache__" not in p.parts)


def _needs_native(tree):
    for node in tree.body:
        targets = (
            node.targets
            if isinstance(node, ast.Assign)
            else [node.target]
            if isinstance(node, ast.AnnAssign)
            else []
        )
        for target in targets:
            if isinstance(target, ast.Name) and target.id == "NEEDS_NATIVE":
                return isinstance(node.value, ast.Constant) and node.value.value is True
    return False


def _why_not_runnable(node):
    """Why a test definition cannot run under MicroPython, or None: there is no pytest there."""
    if isinstance(node, ast.ClassDef):
        return "test classes are not run under MicroPython; write plain `def test_*():` functions"
    if isinstance(node, ast.AsyncFunctionDef):
        return "`async def` tests are not run under MicroPython; write plain `def test_*():` functions"
    args = node.args
    if args.posonlyargs or args.args or args.kwonlyargs or args.vararg or args.kwarg:
        return (
            "runtime tests take no arguments: MicroPython has no pytest fixtures or parametrize; "
            "use fakes.reset()'s fresh board and a loop inside the test instead"
        )
    return None


def _runtime_test_files():
    """(file relative to tests/openbricks, needs_native, [(test name, why not runnable or None)])."""
    found = []
    for path in sorted(RUNTIME_TESTS_DIR.rglob("test_*.py")):
        if "__pycache__" in path.parts:
            continue
        file = path.relative_to(RUNTIME_TESTS_DIR).as_posix()
        try:
            tree = ast.parse(path.read_text(encoding="utf-8"), filename=str(path))
        except SyntaxError as exc:
            # One failing entry for the file keeps the rest of the MicroPython results reported.
            found.append((file, False, [("<module>", f"does not parse: {exc}")]))
            continue
        tests = []
        for node in tree.body:
            if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)) and node.name.startswith("test_"):
                tests.append((node.name, _why_not_runnable(node)))
            elif isinstance(node, ast.ClassDef) and node.name.startswith("Test"):
                tests.append((node.name, _why_not_runnable(node)))
        found.append((file, _needs_native(tree), tests))
    return found


def _test_params():
    params = []
    for file, needs_native, tests in _runtime_test_files():
        if needs_native:
            continue  # uses the host-only native binding: CPython runs it (see the session header)
        for name, problem in tests:
            params.append(pytest.param(file, name, problem, id=f"mpy::{file}::{name}"))
    return params


RUNTIME_MODULES = _runtime_modules()
TEST_PARAMS = _test_params()


class MicroPythonRun:
    """The results of one run_tests.mjs run, looked up by test and by module."""

    def __init__(self, report):
        self.report = report
        version = (report.get("interpreter") or {}).get("version", "?")
        self.interpreter = f"MicroPython {version}"
        self.tests = {(t["file"], t["name"]): t for t in report["tests"]}
        self.imports = {i["module"]: i for i in report["imports"]}


def _require(condition, message):
    if not condition:
        pytest.fail(message, pytrace=False)


@pytest.fixture(scope="session")
def micropython_run(tmp_path_factory):
    node = shutil.which("node")
    _require(
        node is not None,
        "Node.js not found on PATH: the runtime tests run under MicroPython in Node 20; "
        "install Node.js and run `make setup`",
    )
    _require(
        (INTERPRETER_PACKAGE / "micropython.mjs").exists(),
        f"the MicroPython WebAssembly interpreter is not installed ({INTERPRETER_PACKAGE}): run `make setup`",
    )
    out = tmp_path_factory.mktemp("micropython") / "results.json"
    command = [
        node,
        str(RUNNER),
        "--json",
        str(out),
        "--step-timeout-ms",
        str(STEP_LIMIT_S * 1000),
        "--total-timeout-ms",
        str(RUN_LIMIT_S * 1000),
    ]
    try:
        proc = subprocess.run(command, cwd=REPO, capture_output=True, text=True, timeout=RUN_LIMIT_S + 30)
    except subprocess.TimeoutExpired:
        pytest.fail(f"the MicroPython run did not finish within {RUN_LIMIT_S + 30} s: {' '.join(command)}")
    _require(
        proc.returncode in (0, 1) and out.exists(),
        f"the MicroPython run itself broke (exit {proc.returncode}): {' '.join(command)}\n{proc.stderr}",
    )
    report = json.loads(out.read_text(encoding="utf-8"))
    _require(not report.get("fatal"), f"the MicroPython run itself broke: {report.get('fatal')}")
    return MicroPythonRun(report)


def _failure(run, what, result):
    error = (result.get("error") or "").rstrip()
    text = f"{what} failed under {run.interpreter}:\n{error}"
    if result.get("output"):
        text += "\n--- output ---\n" + result["output"].rstrip()
    return text


@pytest.mark.parametrize(("file", "name", "problem"), TEST_PARAMS)
def test_runtime_test_passes_on_micropython(micropython_run, file, name, problem):
    _require(problem is None, f"{file}::{name}: {problem}")
    result = micropython_run.tests.get((file, name))
    _require(
        result is not None,
        f"{file}::{name} was not run under MicroPython: it is not a module-level function there "
        "(defined conditionally, or deleted at import?)",
    )
    _require(result["outcome"] == "passed", _failure(micropython_run, f"{file}::{name}", result))


@pytest.mark.parametrize("module", RUNTIME_MODULES, ids=["import::" + m for m in RUNTIME_MODULES])
def test_runtime_module_imports_on_micropython(micropython_run, module):
    result = micropython_run.imports.get(module)
    _require(result is not None, f"import {module} was not checked under MicroPython")
    _require(result["outcome"] == "passed", _failure(micropython_run, f"import {module}", result))


def test_micropython_run_covered_what_pytest_collected(micropython_run):
    """The runner (regex scan) and this bridge (ast scan) agree on what runs, and nothing that ran
    unannounced (a test made by assignment) failed."""
    report = micropython_run.report
    native_here = sorted(file for file, needs_native, _ in _runtime_test_files() if needs_native)
    _require(
        sorted(report["needs_native"]) == native_here,
        f"NEEDS_NATIVE files: the runner (discover.mjs) found {sorted(report['needs_native'])}, "
        f"this bridge found {native_here}; write it as `NEEDS_NATIVE = True` at module level",
    )
    collected = {(p.values[0], p.values[1]) for p in TEST_PARAMS if p.values[1] is not None}
    unannounced = [t for t in report["tests"] if (t["file"], t["name"]) not in collected]
    failed = [f"{t['file']}::{t['name']}\n{t.get('error')}" for t in unannounced if t["outcome"] != "passed"]
    _require(not failed, "tests found only at run time failed under MicroPython:\n" + "\n".join(failed))
