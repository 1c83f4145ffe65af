"""The native control cores, imported only when first used.

`from openbricks._native import Servo` is the one way runtime code reaches `_openbricks_native` (the
C cores compiled into the firmware; on CPython the simulator and the tests provide the host build under
the same name). The import happens on first attribute access, not when this module loads, so every
module that mentions the cores still imports on a MicroPython build without them (the WebAssembly
interpreter of the tests); using a core there raises an ImportError that says what is missing.
"""

NAMES = (
    "motor_process",
    "Servo",
    "TrapezoidalProfile",
    "Observer",
    "DriveBase",
    "ImuYaw",
    "PCNTEncoder",
    "ICM45686",
    "HBridge",
    "scs",
    "serial_bus",
    "MotorIO",
    "interrupt_main",
    "ticks_itself",
)


_MISSING = (
    "the native control cores (_openbricks_native) are not in this MicroPython build: "
    "flash an openbricks firmware image, or run the program in the openbricks simulator"
)


def _module():
    try:
        import _openbricks_native
    except ImportError:
        raise ImportError(_MISSING) from None
    if _openbricks_native is None:  # hidden through sys.modules: MicroPython's import returns the None
        raise ImportError(_MISSING)
    return _openbricks_native


def available():
    """True when this interpreter has the native control cores."""
    try:
        _module()
    except ImportError:
        return False
    return True


def _check_name(name):
    if name not in NAMES:
        raise AttributeError("openbricks._native has no %r; the cores are %s" % (name, ", ".join(NAMES)))


def get(name):
    """The core or hook `name`, or None where this interpreter has no such thing: for what the runtime
    does without (an older firmware, the WebAssembly interpreter of the tests, a host build)."""
    _check_name(name)
    try:
        return getattr(_module(), name, None)
    except ImportError:
        return None


def __getattr__(name):
    _check_name(name)
    value = getattr(_module(), name, None)
    if value is None:
        raise ImportError(
            "this build's _openbricks_native has no %s: the firmware is older than the runtime; "
            "reflash it with `openbricks flash`" % name
        )
    # Kept as a module attribute: the next `_native.name` is a plain lookup, not this call. Drivers
    # reach the cores on their hot paths, and on a hub every Python call costs CPU time.
    globals()[name] = value
    return value
