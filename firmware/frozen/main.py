"""Frozen main.py: what a hub does at power-up.

Wire the hub of this board (BLE restored from NVS, the REPL bridge up when it is on, the BLE
button and status LED watched), then hand over to the launcher, which waits for the program button
for the rest of the uptime. A host's Ctrl-C ends this script and leaves the hub at the REPL; the
watchers keep running on their timers.

A user's /main.py in the filesystem replaces all of this.
"""

import sys

try:
    _user_main = open("/main.py").read()
except OSError:
    _user_main = None

if _user_main is not None:
    # In this module's globals, which are the REPL's, as a filesystem main.py would be.
    exec(_user_main)
else:
    from openbricks import hub, launcher

    try:
        hub.for_this_board()
    except Exception as err:
        # A broken radio or LED must not cost the program button and the USB REPL.
        sys.print_exception(err)
    launcher.run()
