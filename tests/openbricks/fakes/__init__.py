"""Hardware fakes for the hub runtime's tests, on CPython and on MicroPython.

install() puts them where the runtime imports them from (`machine`, `esp32`,
`micropython`, the MicroPython `time` surface, and `_openbricks_native` from
the host extension on CPython); reset() gives every test a fresh board.
"""

import sys

from . import clock, esp32, machine

_IS_MICROPYTHON = sys.implementation.name == "micropython"


def install():
    sys.modules["machine"] = machine
    sys.modules["esp32"] = esp32
    sys.modules["time"] = clock
    if not _IS_MICROPYTHON:
        from . import framebuf, micropython

        sys.modules["micropython"] = micropython
        sys.modules["framebuf"] = framebuf  # built into MicroPython
        try:
            import openbricks_native

            sys.modules["_openbricks_native"] = openbricks_native
        except ImportError:
            pass


def reset():
    clock.reset()
    esp32.reset()
    machine.board.reset()
    # Runtime state one test's drivers leave behind (GPIO claims, an engaged e-stop and its halt
    # callbacks) must not leak into the next test.
    pins = sys.modules.get("openbricks.pins")
    if pins is not None:
        pins.reset_claims()
    estop = sys.modules.get("openbricks.estop")
    if estop is not None:
        estop.clear(0)
