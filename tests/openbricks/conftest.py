"""The hub runtime's tests on CPython: fakes installed once, a fresh board per test.

The same test files run under the real MicroPython interpreter
(tests/micropython), so they are plain functions with asserts and no fixtures.
"""

import pytest

import fakes

fakes.install()


@pytest.fixture(autouse=True)
def _fresh_board():
    fakes.reset()
    yield
