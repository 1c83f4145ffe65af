"""The MicroPython side of the runtime test run: imports, test calls and their outcomes.

Runs inside the WebAssembly MicroPython interpreter (worker.mjs drives it one
call at a time, so the Node side can time out a single test). It plays the
part tests/openbricks/conftest.py plays under pytest: the fakes are installed
once, and fakes.reset() runs before every test. Every call returns a JSON
string, because that is the one value both sides read the same way.

Test modules are imported by their package name (tests.openbricks.drivers.
test_st3215) from the repository root, so tracebacks show repository paths.
Between test modules the runtime and test modules are dropped from
sys.modules: each module starts from a fresh import, as it would after a
reboot, and the heap they held can be collected.
"""

import gc
import io
import json
import sys

# The simulator's hardware model (sim/shim), which the fakes build on, imports as `shim` here:
# the simulator package around it is CPython's.
sys.path.append("sim")

import fakes  # noqa: E402 - after the path set-up

fakes.install()

# Module-name prefixes owned by the code under test; everything else (the fakes, the interpreter's
# own modules) stays loaded for the whole run.
_UNDER_TEST = ("openbricks", "tests")

_loaded = {"module": None, "tests": {}}


def _is_under_test(name):
    for prefix in _UNDER_TEST:
        if name == prefix or name.startswith(prefix + "."):
            return True
    return False


def _drop_modules_under_test():
    for name in [n for n in sys.modules if _is_under_test(n)]:
        del sys.modules[name]
    gc.collect()


_HARNESS_FRAME = '  File "' + __file__ + '"'


def _source_line(path, line_no):
    # Read afresh each time (only failures get here): a test may rewrite a file it staged, such as
    # a program under /tmp, between two tracebacks that name the same path.
    try:
        with open(path) as f:
            lines = f.read().split("\n")
    except OSError:
        return ""
    if 0 < line_no <= len(lines):
        return lines[line_no - 1].strip()
    return ""


def _traceback(exc):
    """MicroPython's traceback, with each frame's source line added as CPython prints it: a bare
    `assert` fails with no message here (no pytest rewriting), so the line is the message."""
    buf = io.StringIO()
    sys.print_exception(exc, buf)
    out = []
    for line in buf.getvalue().split("\n"):
        if line.startswith(_HARNESS_FRAME):
            continue
        out.append(line)
        if line.startswith('  File "') and '", line ' in line:
            path, rest = line[len('  File "') :].split('", line ', 1)
            number = rest.split(",", 1)[0]
            if number.isdigit():
                source = _source_line(path, int(number))
                if source:
                    out.append("    " + source)
    return "\n".join(out)


def _import(name):
    __import__(name)
    return sys.modules[name]


def check_import(name):
    """Import runtime module `name` from scratch (its package and dependencies included)."""
    _drop_modules_under_test()
    fakes.reset()
    try:
        _import(name)
    except BaseException as exc:  # noqa: B036 - an import may raise anything, SystemExit included
        return json.dumps({"ok": False, "error": _traceback(exc)})
    finally:
        _drop_modules_under_test()
    return json.dumps({"ok": True})


def load_tests(name, names_json):
    """Import test module `name` and list its test functions.

    `names_json` lists the test functions in order of definition in the
    source file (MicroPython's module dict has no order); test functions the source scan did not see, such
    as ones made by assignment, follow in name order.
    """
    names_in_source_order = json.loads(names_json)
    _drop_modules_under_test()
    _loaded["module"] = None
    _loaded["tests"] = {}
    fakes.reset()
    try:
        module = _import(name)
    except BaseException as exc:  # noqa: B036
        return json.dumps({"ok": False, "error": _traceback(exc)})
    found = {}
    for attr in dir(module):
        if attr.startswith("test_"):
            value = getattr(module, attr)
            if callable(value):
                found[attr] = value
    ordered = [n for n in names_in_source_order if n in found]
    ordered += sorted(n for n in found if n not in ordered)
    _loaded["module"] = module
    _loaded["tests"] = found
    return json.dumps({"ok": True, "tests": ordered})


def _run_scheduled_callbacks():
    # micropython.schedule() callbacks run at the VM's next pending check (a backward jump), so
    # what the test left scheduled runs, and prints, inside the test rather than in the next one.
    for _ in range(2):
        pass


def run_test(test_name):
    """Run one test of the loaded module on a fresh board; outcome 'passed' or 'failed'."""
    fn = _loaded["tests"][test_name]
    fakes.reset()
    try:
        fn()
        _run_scheduled_callbacks()
    except BaseException as exc:  # noqa: B036 - a test may end in SystemExit or KeyboardInterrupt
        return json.dumps({"outcome": "failed", "error": _traceback(exc)})
    finally:
        gc.collect()
    return json.dumps({"outcome": "passed"})


def unload_tests():
    _loaded["module"] = None
    _loaded["tests"] = {}
    _drop_modules_under_test()
    return json.dumps({"ok": True})


def interpreter():
    impl = sys.implementation
    return json.dumps(
        {
            "name": impl.name,
            "version": ".".join(str(v) for v in impl.version[:3]),
            "machine": getattr(impl, "_machine", ""),
            "platform": sys.platform,
        }
    )
