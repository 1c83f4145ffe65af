"""The virtual hub's frozen boot.py and main.py: what the firmware's (firmware/frozen/) do at reset.

They run as hub code in the REPL's namespace, under their frozen names, so what a host sees after
a reset (a user's /boot.py and /main.py honoured, the board wired, the launcher serving the program
button until a Ctrl-C) matches a flashed hub. The firmware tree is not installed with the Python
package, hence this copy; keep the two in step.
"""

BOOT_PY = """\
import micropython

micropython.alloc_emergency_exception_buf(256)

try:
    _user_boot = open("/boot.py").read()
except OSError:
    _user_boot = None
if _user_boot is not None:
    exec(_user_boot)
del _user_boot
"""

MAIN_PY = """\
import sys

try:
    _user_main = open("/main.py").read()
except OSError:
    _user_main = None

if _user_main is not None:
    exec(_user_main)
else:
    from openbricks import hub, launcher

    try:
        hub.for_this_board()
    except Exception as err:
        sys.print_exception(err)
    launcher.run()
"""
