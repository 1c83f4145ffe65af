"""Hardware fakes for the hub runtime's tests, on CPython and on MicroPython.

install() puts them where the runtime imports them from (`machine`, `esp32`,
`micropython`, the MicroPython `time` surface, and `_openbricks_native` from
the host extension on CPython); reset() gives every test a fresh board.
Where the simulator's model of the hardware (sim/shim, through fakes.hardware)
serves, it is installed as it is.
"""

import sys

from . import bluetooth, clock, dupterm, hardware, machine
from .hardware import esp32, mptime, neopixel

_IS_MICROPYTHON = sys.implementation.name == "micropython"
_BOARD_RUNTIME = (
    "openbricks.ble_repl",
    "openbricks.bluetooth",
    "openbricks.bluetooth_button",
    "openbricks.hub",
    "openbricks.launcher",
)


def _print_exception(exc, file=None):
    import traceback

    traceback.print_exception(type(exc), exc, exc.__traceback__, file=sys.stdout if file is None else file)


def install():
    sys.modules["machine"] = machine
    sys.modules["esp32"] = esp32
    sys.modules["time"] = mptime
    sys.modules["bluetooth"] = hardware.bluetooth
    sys.modules["neopixel"] = neopixel
    dupterm.install()
    if not _IS_MICROPYTHON:
        from openbricks_sim.shim import framebuf, micropython

        from . import deflate

        sys.modules["micropython"] = micropython
        sys.modules["framebuf"] = framebuf  # built into MicroPython
        sys.modules["deflate"] = deflate  # built into MicroPython
        if not hasattr(sys, "print_exception"):
            sys.print_exception = _print_exception  # built into MicroPython
        try:
            import openbricks_native

            sys.modules["_openbricks_native"] = openbricks_native
        except ImportError:
            pass


def reset():
    time_now = clock.reset()
    if not _IS_MICROPYTHON:
        from openbricks_sim.shim import micropython  # MicroPython has its own scheduler

        micropython.bind(time_now)  # a soft reset drops whatever was still queued
    esp32.bind({})  # a fresh, empty flash
    machine.board.reset()
    bluetooth.reset()
    dupterm.reset()
    # Runtime state one test's drivers leave behind (GPIO and timer claims, an engaged e-stop and its halt
    # callbacks) must not leak into the next test.
    pins = sys.modules.get("openbricks.pins")
    if pins is not None:
        pins.reset_claims()
    timers = sys.modules.get("openbricks.timers")
    if timers is not None:
        timers.reset_claims()
    estop = sys.modules.get("openbricks.estop")
    if estop is not None:
        estop.clear(0)
    # A servo bus a DriveBase handed to the bus engine, and the engine and controllers left
    # subscribed to the native scheduler, belong to the test that built them.
    st3215 = sys.modules.get("openbricks.drivers.st3215")
    if st3215 is not None:
        st3215.forget_buses()
    native = sys.modules.get("_openbricks_native")
    process = getattr(native, "motor_process", None)
    if process is not None:
        process.reset()
    # The board-level runtime's singletons (BLE bridge, state listeners, the wired hub) point at
    # the radio and timers just replaced.
    for name in _BOARD_RUNTIME:
        module = sys.modules.get(name)
        if module is not None:
            module.reset_state()
