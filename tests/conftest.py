"""Suite-wide pytest configuration."""

import os
import signal
import tempfile

# A suite started in the background of a script inherits SIGINT ignored, and so would every command it
# starts: the tests that press Ctrl-C on a command would then wait for nothing. Give Ctrl-C back.
if signal.getsignal(signal.SIGINT) is signal.SIG_IGN:
    signal.signal(signal.SIGINT, signal.default_int_handler)

# A console running on this computer publishes itself in the runtime dir, and `openbricks` commands go
# through it when they find it: the suite gets a runtime dir of its own, so its commands never do.
os.environ["OPENBRICKS_RUNTIME_DIR"] = tempfile.mkdtemp(prefix="openbricks-test-run-")
# `sim run` leaves a warm server behind for the runs after it (sim/shared_server.py): the suite's runs
# start cold and leave nothing running; tests/sim/test_shared_server.py turns it on and stops it.
os.environ["OPENBRICKS_SIM_WARM"] = "0"


def pytest_collection_modifyitems(config, items):
    """Run the fast unit tests first and the slow end-to-end ones last, in one session."""
    items.sort(key=lambda item: item.get_closest_marker("e2e") is not None)


def _hypothesis_profiles():
    """Under CI the property tests replay a fixed set of examples, so a landing is judged on the
    code, not on which random examples a run happened to draw; locally they explore afresh."""
    import os

    from hypothesis import settings

    settings.register_profile("ci", derandomize=True, print_blob=True)
    if os.environ.get("CI"):
        settings.load_profile("ci")


_hypothesis_profiles()
