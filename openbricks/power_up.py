"""What a hub does at reset: the frozen boot.py and main.py of the image call `boot` and `main`.

Written once here, in the runtime, because two kinds of hub power up: a flashed one (its frozen
one-line firmware/frozen/*.py) and a virtual one (the simulator runs the same one-liners at its reset),
and both must honour a user's /boot.py and /main.py, wire the board and serve the program button alike.
Each takes the frozen script's globals, which are the REPL's, and runs a user's file in them, as a
filesystem boot.py or main.py would be run.
"""

import sys


def _read(path):
    try:
        with open(path) as f:
            return f.read()
    except OSError:
        return None


def boot(namespace):
    """Once after every reset, before main: room for interrupt-handler tracebacks, then /boot.py."""
    import micropython

    # Room to report an exception raised in an interrupt handler instead of a bare MemoryError.
    micropython.alloc_emergency_exception_buf(256)
    source = _read("/boot.py")
    if source is not None:
        exec(source, namespace)


def main(namespace):
    """A user's /main.py replaces everything else. Without one: wire the hub of this board (BLE
    restored from NVS, the REPL bridge up when it is on, the BLE button and status LED watched),
    then hand over to the launcher, which waits for the program button for the rest of the uptime.
    A host's Ctrl-C ends this and leaves the hub at the REPL; the watchers keep running on their
    timers."""
    source = _read("/main.py")
    if source is not None:
        exec(source, namespace)
        return
    from openbricks import hub, launcher

    try:
        hub.for_this_board()
    except Exception as err:
        # A broken radio or LED must not cost the program button and the USB REPL.
        sys.print_exception(err)
    launcher.run()
