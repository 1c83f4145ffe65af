"""The MicroPython surface a hub program imports, provided on CPython by the simulator.

    with Shim(simulation):
        exec(program)            # `import machine, time` now reach the simulated hub

Installing puts the simulator's `machine`, `time`, `micropython`, `esp32`,
`bluetooth`, `neopixel`, `framebuf` and `_openbricks_native` into sys.modules, and takes
any already-imported hub runtime (`openbricks`, `openbricks.*`) out of the
way so the program imports a fresh copy bound to these modules. Uninstalling
puts every one of those entries back as it was and drops the copies the
program imported, so the process that ran the program is left as it found
it. Still, this patches process-wide state: run programs in a process of
their own (sim.run does), never in a daemon or CLI process.

The modules themselves are the one model of the hub's hardware: the runtime's tests run on them too,
under CPython and under MicroPython (tests/openbricks/fakes put test fixtures on top). So they keep
to MicroPython's language, and this package imports none of them until a simulated hub installs.
"""

import sys

SHIMMED = (
    "machine",
    "time",
    "micropython",
    "esp32",
    "bluetooth",
    "neopixel",
    "framebuf",
    "_openbricks_native",
)
_RUNTIME_PACKAGE = "openbricks"


def native_module(serial_bus):
    """`_openbricks_native` as a simulated hub has it: the control cores plus the sim's serial_bus()."""
    import types

    import openbricks_native

    module = types.ModuleType("_openbricks_native", openbricks_native.__doc__)
    for name in dir(openbricks_native):
        if not name.startswith("__"):
            setattr(module, name, getattr(openbricks_native, name))
    module.serial_bus = serial_bus
    # The physics step ticks motor_process (as the firmware's hard tick does on a hub): the runtime
    # must not start a Timer tick of its own (openbricks.robotics.tick asks this).
    module.ticks_itself = True
    return module


def print_exception(exc, file=None):
    """MicroPython's sys.print_exception(exc, file=sys.stdout): the runtime prints tracebacks with it."""
    import traceback

    traceback.print_exception(type(exc), exc, exc.__traceback__, file=sys.stdout if file is None else file)


def _is_runtime(name):
    return name == _RUNTIME_PACKAGE or name.startswith(_RUNTIME_PACKAGE + ".")


class ShimBusyError(RuntimeError):
    pass


_installed = [None]


class Shim:
    """Installs the simulated hub's modules for `simulation` (needs .clock, .board, .nvs, .serial_bus)."""

    def __init__(self, simulation):
        self._simulation = simulation
        self._saved = None

    def install(self):
        if _installed[0] is not None:
            raise ShimBusyError("a simulated hub's modules are already installed in this process")
        from . import bluetooth, esp32, framebuf, machine, micropython, mptime, neopixel

        sim = self._simulation
        saved_modules = {name: sys.modules.get(name) for name in SHIMMED}
        saved_runtime = {name: module for name, module in sys.modules.items() if _is_runtime(name)}
        for name in saved_runtime:
            del sys.modules[name]
        self._saved = (saved_modules, saved_runtime)
        machine.bind(sim.board)
        mptime.bind(sim.clock)
        micropython.bind(sim.clock)
        esp32.bind(sim.nvs)
        bluetooth.reset()
        sys.modules.update(
            {
                "machine": machine,
                "time": mptime,
                "micropython": micropython,
                "esp32": esp32,
                "bluetooth": bluetooth,
                "neopixel": neopixel,
                "framebuf": framebuf,
                "_openbricks_native": native_module(sim.serial_bus),
            }
        )
        self._added_print_exception = not hasattr(sys, "print_exception")
        if self._added_print_exception:
            sys.print_exception = print_exception
        _installed[0] = self
        return self

    def uninstall(self):
        if self._saved is None:
            return
        saved_modules, saved_runtime = self._saved
        self._saved = None
        from . import esp32, machine, micropython, mptime

        for name in [name for name in sys.modules if _is_runtime(name)]:
            del sys.modules[name]
        sys.modules.update(saved_runtime)
        for name, module in saved_modules.items():
            if module is None:
                sys.modules.pop(name, None)
            else:
                sys.modules[name] = module
        machine.bind(None)
        mptime.bind(None)
        micropython.bind(None)
        esp32.bind(None)
        if self._added_print_exception:
            del sys.print_exception
        _installed[0] = None

    def host_modules(self):
        """A context in which sys.modules has the host's own entries for the shimmed names again (the
        simulator importing MuJoCo in the middle of a program must get the host's `time`)."""
        import contextlib

        @contextlib.contextmanager
        def swapped():
            saved_modules = self._saved[0] if self._saved is not None else {}
            shimmed = {name: sys.modules.get(name) for name in saved_modules}
            for name, module in saved_modules.items():
                if module is None:
                    sys.modules.pop(name, None)
                else:
                    sys.modules[name] = module
            try:
                yield
            finally:
                for name, module in shimmed.items():
                    if module is None:
                        sys.modules.pop(name, None)
                    else:
                        sys.modules[name] = module

        return swapped()

    def __enter__(self):
        return self.install()

    def __exit__(self, *exc):
        self.uninstall()
        return False
