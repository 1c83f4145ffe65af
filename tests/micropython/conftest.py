"""Says in the session header which runtime test files run on CPython only."""

from .test_runtime_on_micropython import _runtime_test_files


def pytest_report_header(config):
    native = sorted(file for file, needs_native, _ in _runtime_test_files() if needs_native)
    if native:
        return f"runtime tests on CPython only (NEEDS_NATIVE, host-only native binding): {', '.join(native)}"
    return None
