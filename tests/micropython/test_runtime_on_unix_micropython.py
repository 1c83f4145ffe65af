"""The hub runtime's tests on MicroPython's unix port with the real `_openbricks_native` compiled in.

The runtime test files run here on a MicroPython whose `_openbricks_native` is the hub binding
(firmware/native/user_c_modules) built from real MicroPython sources by `make micropython` (`make
test` builds it first), one interpreter process per file, and the binding's smoke script
(firmware/binding_smoke.py) must give the host extension's numbers.
"""

import importlib.util
import json
import os
import subprocess
from pathlib import Path

import pytest

from .test_runtime_on_micropython import REPO, _module_name, _runtime_test_files

INTERPRETER = Path(
    os.environ.get("OPENBRICKS_UNIX_MICROPYTHON", REPO / "build" / "micropython" / "micropython")
)
RUNNER = Path(__file__).resolve().parent / "unix_run.py"
FILE_LIMIT_S = 280  # inside pytest-timeout's 300 s; a loaded machine runs a long drive file for minutes
# Objects on this 64-bit host are twice the ESP32's size, and the fakes' long-lived traffic logs
# fragment the heap over a long simulated drive; the hub's own memory limits are not what is tested.
HEAP = "heapsize=64M"

pytestmark = pytest.mark.micropython


def _load_check():
    path = REPO / "firmware" / "check_micropython_binding.py"
    spec = importlib.util.spec_from_file_location("check_micropython_binding", path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


check = _load_check()


def _files():
    # Every runtime test file, NEEDS_NATIVE ones included: this interpreter has the cores.
    return [
        (file, [name for name, problem in tests if problem is None])
        for file, _, tests in _runtime_test_files()
    ]


@pytest.fixture(scope="session")
def unix_micropython():
    if not INTERPRETER.is_file():
        pytest.fail(
            f"the unix MicroPython with _openbricks_native is not built ({INTERPRETER}): "
            "run `make micropython` (or `make test`, which builds it)",
            pytrace=False,
        )
    return INTERPRETER


def run_file(interpreter, file, names):
    module = _module_name(REPO / "tests" / "openbricks" / file)
    try:
        proc = subprocess.run(
            [str(interpreter), "-X", HEAP, str(RUNNER), module],
            input=json.dumps(names),
            cwd=REPO,
            capture_output=True,
            text=True,
            timeout=FILE_LIMIT_S,
        )
    except subprocess.TimeoutExpired as err:
        return {}, f"{file} did not finish within {FILE_LIMIT_S} s:\n{err.stdout or ''}"
    results = {}
    for line in proc.stdout.splitlines():
        if line.startswith("@result "):
            result = json.loads(line[len("@result ") :])
            results[result["name"]] = result
    return results, f"exit {proc.returncode}\n{proc.stdout[-4000:]}{proc.stderr[-4000:]}"


@pytest.mark.parametrize(("file", "names"), _files(), ids=[f"unix::{file}" for file, _ in _files()])
def test_runtime_file_passes_on_unix_micropython(unix_micropython, file, names):
    results, output = run_file(unix_micropython, file, names)
    if "<module>" in results:
        pytest.fail(
            f"importing {file} failed on the unix MicroPython:\n{results['<module>']['error']}", pytrace=False
        )
    missing = [name for name in names if name not in results]
    failed = [
        f"{name}:\n{results[name]['error']}"
        for name in names
        if name in results and results[name]["outcome"] != "passed"
    ]
    if missing or failed:
        text = "\n".join(failed)
        if missing:
            text += f"\nnot run: {', '.join(missing)}\n--- interpreter output ---\n{output}"
        pytest.fail(f"{file} on the unix MicroPython with _openbricks_native:\n{text}", pytrace=False)


def test_the_binding_smoke_script_matches_the_host_extension(unix_micropython):
    """firmware/binding_smoke.py, the runtime's use of the binding in miniature, computes the same on both."""
    hub = check.smoke_values([str(unix_micropython), str(check.SMOKE)])
    host = check.smoke_values(check.host_command())
    assert check.disagreements(hub, host) == []
