"""The runtime tests' virtual clock stays inside their folder (regression: it leaked into host tests)."""

import sys
import time


def test_host_tests_see_the_real_time_module():
    assert sys.modules["time"] is time
    assert time.sleep.__module__ == "time"
    before = time.monotonic()
    time.sleep(0.01)
    assert time.monotonic() - before >= 0.009
