"""The hub a sim run's program sees: MicroPython's `os`, `open` and `sys` on a flash of its own.

    with Shim(simulation), RunFlash(hub_dir=None) as flash:   # None: a fresh temporary flash
        exec(code, flash.program_globals("mission.py"))

A program written for the hub opens hub paths ("/qtr.cal", "/openbricks_logs/slot_0.log"). Run on
the host as they are, those would land in the host's root. So a run gets the virtual hub's Python
(virtual_hub/hub_python.py over a HubFS): its own builtins, whose `open` and `import os` reach the
flash directory and never leave it, a MicroPython `sys`, and modules on the flash importable as on
the hub. The runtime (`openbricks`) is loaded with the same builtins, so its own files (run logs,
the QTR calibration, staged programs) land on that flash too.

By default the flash is a temporary directory made for the run and removed after it: every run
starts on a blank hub, as a job must to be repeatable. Given `hub_dir`, the run uses that directory
as the hub's root and leaves what the program wrote there, so a calibration saved by one run is
read by the next.
"""

import os
import shutil
import tempfile

from .shim import mptime
from .virtual_hub.hub_fs import HubFS
from .virtual_hub.hub_python import HubPython

# What `sys.implementation._machine` reports: the pins guard then checks the ESP32-S3's pin rules,
# so a pin the real hub refuses is refused in the simulator too.
MACHINE = "openbricks simulator with ESP32S3"


class HubDirError(ValueError):
    """The hub directory given for a run cannot hold a flash."""


def prepare_hub_dir(hub_dir):
    """Create `hub_dir` if missing; HubDirError naming the path and the fix if it cannot be a flash.

    Called before a run is set up, so a typo fails in one line instead of a traceback mid-run.
    """
    if hub_dir is None:
        return None
    path = os.fspath(hub_dir)
    if os.path.exists(path) and not os.path.isdir(path):
        raise HubDirError(f"hub directory {path} is a file: give a directory for the hub's flash")
    try:
        os.makedirs(path, exist_ok=True)
    except OSError as exc:
        raise HubDirError(f"cannot use {path} as the hub's flash: {exc.strerror or exc}") from None
    return path


class RunFlash:
    """The hub flash and hub Python of one program run (a context manager, entered after the Shim)."""

    def __init__(self, hub_dir=None):
        self.hub_dir = prepare_hub_dir(hub_dir)
        self.fs = None
        self.python = None
        self._temporary = None

    def __enter__(self):
        root = self.hub_dir
        if root is None:
            root = self._temporary = tempfile.mkdtemp(prefix="openbricks-hub-")
        try:
            self.fs = HubFS(root)
            self.python = HubPython(self.fs, mptime, MACHINE)
            self.python.install()
        except BaseException:
            self._remove_temporary()
            raise
        return self

    def program_globals(self, filename):
        """Globals for the program, run as `__main__` with the hub's builtins."""
        return {"__name__": "__main__", "__file__": filename, "__builtins__": self.python.builtins}

    def __exit__(self, *exc):
        # Modules imported from the flash belong to this run; the Shim restores the runtime modules.
        self.python.forget_modules()
        self.python.uninstall()
        self._remove_temporary()
        return False

    def _remove_temporary(self):
        if self._temporary is not None:
            shutil.rmtree(self._temporary, ignore_errors=True)
            self._temporary = None
