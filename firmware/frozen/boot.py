"""Frozen boot.py: runs once after every reset, before main.py.

A user's /boot.py in the filesystem still runs (after this), since a frozen boot.py would otherwise
hide it.
"""

import micropython

# Room to report an exception raised in an interrupt handler instead of a bare MemoryError.
micropython.alloc_emergency_exception_buf(256)

try:
    _user_boot = open("/boot.py").read()
except OSError:
    _user_boot = None
if _user_boot is not None:
    # In this module's globals, which are the REPL's, as a filesystem boot.py would be.
    exec(_user_boot)
del _user_boot
