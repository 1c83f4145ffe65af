"""The hub runtime's tests on CPython: fakes installed, a fresh board per test.

The same test files run under the real MicroPython interpreter
(tests/micropython), so they are plain functions with asserts and no fixtures.

The fakes replace `time` with the virtual clock. That must not leak into the
host-side tests (a link test's `time.sleep` has to really sleep), so the
virtual clock is in sys.modules only while this folder's test modules are
imported and while its tests run; the rest of the time the host's is.
"""

import sys
from pathlib import Path

import pytest

import fakes

_HOST_TIME = sys.modules["time"]
fakes.install()
sys.modules["time"] = _HOST_TIME
_THIS_FOLDER = Path(__file__).parent


@pytest.hookimpl(wrapper=True)
def pytest_make_collect_report(collector):
    if not Path(collector.path).is_relative_to(_THIS_FOLDER):
        return (yield)
    sys.modules["time"] = fakes.mptime
    try:
        return (yield)
    finally:
        sys.modules["time"] = _HOST_TIME


@pytest.fixture(autouse=True)
def _fresh_board():
    sys.modules["time"] = fakes.mptime
    fakes.reset()
    yield
    sys.modules["time"] = _HOST_TIME
