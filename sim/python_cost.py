"""Python costs simulated time: a program that spins without sleeping still lets the robot move.

On a hub every bytecode takes CPU time while the 1 kHz tick keeps the controllers running, so
`while not db.done(): pass` ends when the move does. In the simulator time passes only when the
program lets it (a sleep, a clock read, a bus transfer); without this, such a loop would hold
simulated time still forever. So each Python function call the program and the hub runtime make
is charged CALL_US of simulated time (what one costs MicroPython on an ESP32-S3), paid to the clock
in slices of BATCH_US. Calls into the simulator's own code (the shim, device models) and the host's
library are the hub's C and cost nothing here, as they are charged their bus time already.

The charge is counted, not measured, so one program always sees the same simulated times.
"""

import os
import sys

# A MicroPython function or method call on a 240 MHz ESP32-S3: a few microseconds with its bytecodes.
CALL_US = 5
# Paid to the clock in slices, so the physics is stepped about once per simulated millisecond of
# spinning rather than once per call.
BATCH_US = 1000

_SIM_DIR = os.path.dirname(os.path.abspath(__file__)) + os.sep
_HOST_DIRS = tuple({os.path.join(p, "") for p in (sys.prefix, sys.base_prefix, sys.exec_prefix)})


def _runtime_dir():
    """Where the hub runtime's files are (found, not imported: the program imports its own copy)."""
    import importlib.util

    spec = importlib.util.find_spec("openbricks")
    return os.path.dirname(os.path.abspath(spec.origin)) + os.sep


class PythonCost:
    """While installed (in the program's thread), the program's and the runtime's calls cost time.

    The counting runs in C (sim/native/python_cost: one read of a slot on the code object per call);
    which code counts and where the time goes is decided here.
    """

    def __init__(self, clock):
        import openbricks_pycost

        self._clock = clock
        self._runtime = _runtime_dir()
        self._cost = openbricks_pycost.Cost(self._counts, clock.charge_cpu_us, CALL_US, BATCH_US)
        self._saved = None

    def _counts(self, filename):
        if filename.startswith(self._runtime):
            return True
        if filename.startswith("<") or filename.startswith(_SIM_DIR):
            return False
        return not filename.startswith(_HOST_DIRS)  # the program, and modules on the hub's flash

    def install(self):
        self._saved = sys.getprofile()
        self._cost.install()
        self._clock.python_cost = self._cost
        return self

    def uninstall(self):
        self._clock.python_cost = None
        self._cost.uninstall()
        if self._saved is not None:
            sys.setprofile(self._saved)
        self._saved = None

    def __enter__(self):
        return self.install()

    def __exit__(self, *exc):
        self.uninstall()
        return False
