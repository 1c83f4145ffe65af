"""The Python that code on a virtual hub sees: MicroPython's os, open, sys and import, on its flash.

The hub process is CPython, and its own machinery (the link threads, MuJoCo, the simulator) must
keep the host's `os`, `open` and `sys`. So hub code gets its own builtins module instead of patched
process-wide modules:

- imports reach only what the hub has: the modules of MicroPython's ESP32 port
  (hub_modules.py, the list the runtime is held to), the runtime, and modules on the flash; any
  other name is `ImportError: no module named 'subprocess'`, as on the hub;
- `open` and `io.open` open files on the hub's flash (HubFS), `import os` / `import uos` give the
  flash's MicroPython `os`, `import sys` a `sys` with MicroPython's attributes only (`path`
  ['', '.frozen', '/lib'], `print_exception`, an `implementation` named 'micropython', a
  `modules` that shows hub modules only), and `import time` the simulator's MicroPython time
  with sleeps paced by the hub (see world.py);
- `import gc` adds MicroPython's mem_free()/mem_alloc() (what is left before a MemoryError);
- `import deflate` gives MicroPython's deflate (the host compresses staged programs with it);
- modules the hub has on its flash (a helper next to the program, a package under /lib) import
  from there, compiled under their hub paths; a `.mpy` is refused with the reason (this hub runs
  source);
- the hub runtime (`openbricks`, frozen into real firmware) is imported with these builtins too, so
  its run logs, staging and launcher work on the flash exactly as on a hub.

Code the REPL runs goes through `HubPython.run()`, and tracebacks print as MicroPython prints
them: frames of hub code only, and MicroPython's exception names (OSError for FileNotFoundError).

This keeps programs on the hub's API; it is not a security boundary (Python code can reach the
interpreter's internals). The process's OS-level fence (limits.contain) is what holds then.
"""

import builtins
import importlib.machinery
import importlib.util
import os
import sys
import types
from collections.abc import MutableMapping

from ..hub_modules import RUNTIME_PACKAGE, hub_name
from . import deflate_module
from .hub_fs import HubFS
from .hub_vfs import HubVFS

FLASH_PATH_PREFIX = "<hub-flash>:"  # marks a package __path__ entry that lives on the hub's flash
DEFAULT_SYS_PATH = ("", ".frozen", "/lib")
HIDDEN_BUILTINS = ("exit", "quit", "copyright", "credits", "license")
# MicroPython 1.27's sys.implementation.version (the port the firmware builds)
MICROPYTHON_VERSION = (1, 27, 0, "")
# What MicroPython's `sys` has; hub code sees these of the host's sys and nothing else.
SYS_ATTRIBUTES = frozenset(
    ("argv", "byteorder", "exc_info", "exit", "maxsize", "modules", "stderr", "stdin", "stdout")
    + ("version", "version_info", "settrace", "tracebacklimit", "ps1", "ps2")
)
# What MicroPython's `io` has; `open` is the flash's.
IO_ATTRIBUTES = ("IOBase", "StringIO", "BytesIO", "BufferedWriter")


# -- tracebacks --------------------------------------------------------------------------------


def exception_name(exc):
    """The name MicroPython gives this exception's class (it has no OSError subclasses)."""
    if isinstance(exc, OSError):
        return "OSError"
    if isinstance(exc, ModuleNotFoundError):
        return "ImportError"
    if isinstance(exc, RecursionError):
        return "RuntimeError"
    return type(exc).__name__


def exception_text(exc):
    if isinstance(exc, OSError) and len(exc.args) == 1 and isinstance(exc.args[0], int):
        import errno

        code = exc.args[0]
        return f"[Errno {code}] {errno.errorcode.get(code, code)}"
    if isinstance(exc, KeyError) and len(exc.args) == 1:
        return repr(exc.args[0])
    return str(exc)


class TracebackFormatter:
    """MicroPython's traceback text for exceptions raised by hub code."""

    def __init__(self, fs: HubFS, runtime_dir=None):
        self._fs = fs
        if runtime_dir is None:
            spec = importlib.util.find_spec(RUNTIME_PACKAGE)
            runtime_dir = os.path.dirname(spec.origin) if spec and spec.origin else None
        self._runtime_parent = os.path.dirname(runtime_dir) + os.sep if runtime_dir else None

    def _shown_name(self, filename):
        """How the hub names a frame's file, or None for host code (hidden, as C is on a hub)."""
        if filename.startswith("<") or not filename.startswith(os.sep):
            return filename  # <stdin>, frozen boot.py / main.py
        if self._runtime_parent and filename.startswith(self._runtime_parent + RUNTIME_PACKAGE + os.sep):
            return filename[len(self._runtime_parent) :].replace(os.sep, "/")  # frozen: openbricks/...
        try:
            if os.path.isfile(self._fs.host_path(filename)):
                return filename  # a hub path (the program, a module on the flash)
        except (OSError, TypeError):
            pass
        return None

    def format(self, exc, program=False):
        """The traceback text; a `program`'s shows its own frames only, without the runtime's
        (as the hub's launcher shows it)."""
        lines = []
        tb = exc.__traceback__
        frames = []
        while tb is not None:
            code = tb.tb_frame.f_code
            shown = self._shown_name(code.co_filename)
            if program and shown is not None and shown.startswith(RUNTIME_PACKAGE + "/"):
                shown = None
            if shown is not None:
                frames.append(f'  File "{shown}", line {tb.tb_lineno}, in {code.co_name}\n')
            tb = tb.tb_next
        if isinstance(exc, SyntaxError) and exc.lineno is not None:
            frames.append(f'  File "{exc.filename}", line {exc.lineno}\n')
        if frames:
            lines.append("Traceback (most recent call last):\n")
            lines.extend(frames)
        if isinstance(exc, SyntaxError):
            lines.append(f"SyntaxError: {exc.msg}\n")
        else:
            lines.append(f"{exception_name(exc)}: {exception_text(exc)}\n")
        return "".join(lines)

    def print_exception(self, exc, file=None):
        """sys.print_exception(exc, file=sys.stdout), MicroPython's API."""
        (file if file is not None else sys.stdout).write(self.format(exc))


# -- imports -----------------------------------------------------------------------------------


class _HubLoader:  # a loader: create_module() and exec_module() (importlib.abc costs its import)
    """Runs a module with the hub's builtins: a runtime module through its own loader, or a file
    from the flash compiled under its hub path."""

    def __init__(self, hub, inner=None, hub_path=None):
        self._hub = hub
        self._inner = inner
        self.hub_path = hub_path

    def create_module(self, spec):
        return self._inner.create_module(spec) if self._inner is not None else None

    def exec_module(self, module):
        module.__dict__["__builtins__"] = self._hub.builtins
        if self._inner is not None:
            self._inner.exec_module(module)
            return
        module.__file__ = self.hub_path
        with self._hub.files.open(self.hub_path, "rb") as f:
            source = f.read()
        self._hub.flash_modules.add(module.__name__)
        exec(compile(source, self.hub_path, "exec"), module.__dict__)

    def is_package(self, fullname):
        return self._inner.is_package(fullname) if self._inner is not None else False

    def get_source(self, fullname):
        if self._inner is not None:
            return self._inner.get_source(fullname)
        with self._hub.files.open(self.hub_path, "r") as f:
            return f.read()


class HubFinder:  # a meta path finder: find_spec() is all the import system asks of one
    """On sys.meta_path of the hub process: the runtime and flash packages' submodules."""

    def __init__(self, hub):
        self._hub = hub

    def find_spec(self, fullname, path=None, target=None):
        if fullname == RUNTIME_PACKAGE or fullname.startswith(RUNTIME_PACKAGE + "."):
            spec = importlib.machinery.PathFinder.find_spec(fullname, path)
            if spec is None or spec.loader is None:
                return None
            spec.loader = _HubLoader(self._hub, inner=spec.loader)
            return spec
        if path:
            flash_dirs = [p[len(FLASH_PATH_PREFIX) :] for p in path if str(p).startswith(FLASH_PATH_PREFIX)]
            if flash_dirs:
                return self._hub.find_on_flash(fullname, flash_dirs)
        return None


class _HubSys(types.ModuleType):
    """`sys` for hub code: MicroPython's attributes, the live ones (stdout, ...) from the host's."""

    def __getattr__(self, name):
        if name in SYS_ATTRIBUTES:
            return getattr(sys, name)
        raise AttributeError(f"'module' object has no attribute '{name}'")


class _HubModules(MutableMapping):
    """`sys.modules` as hub code sees it: the hub modules and flash modules loaded so far (the
    facades for os, sys, ...), never the host's own; deleting one lets it load afresh."""

    def __init__(self, hub):
        self._hub = hub

    def _visible(self, name):
        top = name.partition(".")[0]
        if self._hub._facade(top) is not None:
            return name == top
        return hub_name(top) == top or top in self._hub.flash_modules

    def __getitem__(self, name):
        if not isinstance(name, str) or not self._visible(name):
            raise KeyError(name)
        facade = self._hub._facade(name)
        return facade if facade is not None else sys.modules[name]

    def __setitem__(self, name, module):
        if name in sys.modules and not self._visible(name):
            raise KeyError(name)  # the host's own module of that name stays
        sys.modules[name] = module

    def __delitem__(self, name):
        if not self._visible(name) or self._hub._facade(name) is not None:
            raise KeyError(name)
        del sys.modules[name]

    def __iter__(self):
        return iter([name for name in list(sys.modules) if self._visible(name)])

    def __len__(self):
        return sum(1 for _ in self)


class HubPython:
    """Builtins, module facades and the REPL namespace of one virtual hub."""

    def __init__(self, fs: HubFS, time_module, machine_name, input_fn=None, stdin_ready=None):
        self.fs = fs
        self.files = HubVFS(fs)  # the flash at "/" and what hub code mounts beside it
        self._stdin_ready = stdin_ready  # stdin_ready(timeout_s) -> bool: select.poll on the console
        self.flash_modules = set()  # modules imported from the flash (dropped at a soft reset)
        self._time = time_module
        self._machine_name = machine_name
        self._input = input_fn
        self.traceback = TracebackFormatter(fs)
        self.finder = HubFinder(self)
        self.reset()

    # -- lifecycle ---------------------------------------------------------------------------------

    def install(self):
        """Put the hub's finder first on sys.meta_path (the process now hosts this hub)."""
        if self.finder not in sys.meta_path:
            sys.meta_path.insert(0, self.finder)

    def uninstall(self):
        if self.finder in sys.meta_path:
            sys.meta_path.remove(self.finder)

    def reset(self):
        """A soft reset's fresh Python state: builtins, sys.path, cwd and the REPL namespace.

        Modules are dropped with forget_modules(), separately, because the caller first stops
        what the old runtime left running.
        """
        self.fs.cwd = "/"
        self.files.reset()
        self.os = self.files.os_module()
        self.vfs = self.files.vfs_module()
        self.select = _make_select(self._stdin_ready)
        self.os.dupterm = _no_dupterm
        self.gc = _make_gc()
        self.io = self._make_io()
        self.sys = self._make_sys()
        self.builtins = self._make_builtins()
        self.namespace = {"__name__": "__main__", "__builtins__": self.builtins}

    def forget_modules(self):
        """Drop the runtime and every flash module, so the next import loads them afresh."""
        for name in list(sys.modules):
            if name == RUNTIME_PACKAGE or name.startswith(RUNTIME_PACKAGE + "."):
                del sys.modules[name]
        self.forget_flash_modules()
        importlib.invalidate_caches()

    def forget_flash_modules(self):
        """Drop the modules imported from the flash (a re-uploaded helper then loads fresh)."""
        for name in self.flash_modules:
            sys.modules.pop(name, None)
        self.flash_modules.clear()

    def _make_sys(self):
        module = _HubSys("sys", "MicroPython's sys on the virtual hub.")
        module.path = list(DEFAULT_SYS_PATH)
        module.argv = []
        module.platform = "esp32"
        module.print_exception = self.traceback.print_exception
        module.modules = _HubModules(self)
        module.implementation = types.SimpleNamespace(
            name="micropython", version=MICROPYTHON_VERSION, _machine=self._machine_name
        )
        return module

    def _make_io(self):
        import io

        module = types.ModuleType("io", "MicroPython's io: streams, and open() on the hub's flash.")
        for name in IO_ATTRIBUTES:
            setattr(module, name, getattr(io, name))
        module.open = self.files.open
        return module

    def _make_builtins(self):
        module = types.ModuleType("builtins", builtins.__doc__)
        module.__dict__.update(builtins.__dict__)
        for name in HIDDEN_BUILTINS:
            module.__dict__.pop(name, None)
        module.open = self.files.open
        module.__import__ = self._import
        module.help = _help
        if self._input is not None:
            module.input = self._input
        return module

    # -- imports -------------------------------------------------------------------------------------

    def _facade(self, name):
        name = hub_name(name) or name
        if name == "io":
            return self.io
        if name == "os":
            return self.os
        if name == "sys":
            return self.sys
        if name == "builtins":
            return self.builtins
        if name == "time":
            return self._time
        if name == "deflate":
            return deflate_module
        if name == "vfs":
            return self.vfs
        if name == "select":
            return self.select
        if name == "gc":
            return self.gc
        return None

    def _import(self, name, globals=None, locals=None, fromlist=(), level=0):
        if level == 0:
            top, _, rest = name.partition(".")
            facade = self._facade(top)
            if facade is not None:
                if rest:
                    raise ImportError(f"no module named '{name}'")
                return facade
            hub = hub_name(top)
            if hub is None:
                loaded = top in self.flash_modules and top in sys.modules
                if not loaded and not self._import_from_flash(top):
                    raise ImportError(f"no module named '{name}'")
            elif hub != top:  # a deprecated u-prefixed name: ujson is json
                name = hub + name[len(top) :]
        return builtins.__import__(name, globals, locals, fromlist, level)

    def _search_dirs(self):
        dirs = []
        for entry in self.sys.path:
            if entry == ".frozen" or not isinstance(entry, str):
                continue
            dirs.append(self.fs.hub_path(entry or "."))
        return dirs

    def _import_from_flash(self, name):
        """Import module `name` from the flash's search path; False if it is not there."""
        spec = self.find_on_flash(name, self._search_dirs())
        if spec is None:
            return False
        module = importlib.util.module_from_spec(spec)
        sys.modules[name] = module
        try:
            spec.loader.exec_module(module)
        except BaseException:
            sys.modules.pop(name, None)
            self.flash_modules.discard(name)
            raise
        return True

    def find_on_flash(self, fullname, hub_dirs):
        """The spec of module `fullname` in one of the flash directories, or None."""
        leaf = fullname.rpartition(".")[2]
        for directory in hub_dirs:
            base = directory.rstrip("/") + "/" + leaf
            package_init = base + "/__init__.py"
            if self._is_file(package_init):
                spec = importlib.util.spec_from_loader(
                    fullname, _HubLoader(self, hub_path=package_init), origin=package_init, is_package=True
                )
                spec.submodule_search_locations = [FLASH_PATH_PREFIX + base]
                return spec
            if self._is_file(base + ".py"):
                return importlib.util.spec_from_loader(
                    fullname, _HubLoader(self, hub_path=base + ".py"), origin=base + ".py"
                )
            if self._is_file(base + ".mpy"):
                raise ImportError(
                    f"{base}.mpy is MicroPython bytecode, which a virtual hub cannot load: "
                    f"copy the source ({leaf}.py) to the hub instead"
                )
        return None

    def _is_file(self, hub_path):
        return self.files.is_file(hub_path)

    # -- running code --------------------------------------------------------------------------------

    def compile(self, source, filename="<stdin>", mode="exec"):
        """Compile hub source (bytes or str); SyntaxError as hub code would raise it."""
        if isinstance(source, bytes):
            source = source.decode("utf-8", "replace")
        return compile(source, filename, mode, dont_inherit=True)

    def run(self, code):
        """Execute compiled code in the REPL namespace (the caller handles exceptions)."""
        exec(code, self.namespace)


def _make_gc():
    """`gc` with MicroPython's mem_alloc()/mem_free(): this process's resident memory, and the
    address space left before a MemoryError (the process's limit, else the free physical memory)."""
    import gc
    import resource

    module = types.ModuleType("gc", gc.__doc__)
    for name in ("collect", "enable", "disable", "isenabled"):
        setattr(module, name, getattr(gc, name))
    page = os.sysconf("SC_PAGE_SIZE")

    def _statm():
        with open("/proc/self/statm", "rb") as f:
            size, resident = f.read().split()[:2]
        return int(size) * page, int(resident) * page

    def mem_alloc():
        return _statm()[1]

    def mem_free():
        limit = resource.getrlimit(resource.RLIMIT_AS)[0]
        if limit == resource.RLIM_INFINITY:
            return os.sysconf("SC_AVPHYS_PAGES") * page
        return max(0, limit - _statm()[0])

    module.mem_alloc = mem_alloc
    module.mem_free = mem_free
    module.threshold = lambda amount=None: -1 if amount is None else None
    return module


def _make_select(stdin_ready):
    """MicroPython's `select` for hub code: poll() over the console's stdin (what mpremote's mount
    code waits on); other streams count as always ready, as a file on the flash is."""
    import select as host_select

    module = types.ModuleType("select", "MicroPython's select on the virtual hub.")
    module.POLLIN, module.POLLOUT = host_select.POLLIN, host_select.POLLOUT
    module.POLLERR, module.POLLHUP = host_select.POLLERR, host_select.POLLHUP

    class Poll:
        def __init__(self):
            self._streams = {}

        def register(self, stream, eventmask=host_select.POLLIN | host_select.POLLOUT):
            self._streams[id(stream)] = (stream, eventmask)

        def modify(self, stream, eventmask):
            if id(stream) not in self._streams:
                raise OSError(2, "ENOENT")
            self._streams[id(stream)] = (stream, eventmask)

        def unregister(self, stream):
            self._streams.pop(id(stream), None)

        def poll(self, timeout_ms=-1):
            return list(self.ipoll(timeout_ms))

        def ipoll(self, timeout_ms=-1, flags=0):
            timeout_s = None if timeout_ms is None or timeout_ms < 0 else timeout_ms / 1000
            ready = []
            waits_on_console = False
            for stream, mask in self._streams.values():
                events = mask & host_select.POLLOUT
                if mask & host_select.POLLIN:
                    if _is_console_in(stream):
                        waits_on_console = True
                        continue
                    events |= host_select.POLLIN
                if events:
                    ready.append((stream, events))
            if waits_on_console and stdin_ready is not None:
                console_ready = stdin_ready(0 if ready else timeout_s)
                for stream, mask in self._streams.values():
                    if mask & host_select.POLLIN and _is_console_in(stream) and console_ready:
                        ready.append((stream, host_select.POLLIN))
            return iter(ready)

    module.poll = Poll
    return module


def _is_console_in(stream):
    return getattr(stream, "console_input", False)


def _no_dupterm(stream=None, index=0):
    """os.dupterm(): a virtual hub's console is its pty/stdio link, and it has no radio."""
    import errno

    if stream is None:
        return None
    raise OSError(
        errno.EOPNOTSUPP,
        "a virtual hub has no second terminal to attach (its console is the pty it was started on; "
        "there is no BLE radio): keep BLE off on virtual hubs",
    )


def _help(obj=None):
    if obj is not None:
        print(getattr(obj, "__doc__", None) or f"no help for {obj!r}")
        return
    print(
        "This is an openbricks virtual hub: a simulated ESP32-S3 hub running the openbricks runtime.\n"
        "Programs run against the simulator; the filesystem is the hub's flash.\n\n"
        "Control commands:\n"
        "  CTRL-A        -- on a blank line, enter raw REPL mode\n"
        "  CTRL-B        -- on a blank line, enter normal REPL mode\n"
        "  CTRL-C        -- interrupt a running program\n"
        "  CTRL-D        -- on a blank line, do a soft reset of the board\n"
        "  CTRL-E        -- on a blank line, enter paste mode\n\n"
        "Start with: import openbricks.host_calls as h; h.info()"
    )
