"""The MicroPython binding of the control cores (firmware/native/user_c_modules/openbricks/).

- Its names and methods, read from the C method and attribute tables, are the host extension's,
  except for the differences listed below on purpose.
- The binding compiled into MicroPython's unix port (`make micropython`, from the source release in
  the `shared` folder beside the checkout) runs firmware/binding_smoke.py with the host's results and
  the runtime's tests: tests/micropython/test_runtime_on_unix_micropython.py.
"""

import re
from pathlib import Path

import pytest

import openbricks_native

ROOT = Path(__file__).resolve().parents[2]
MODULE_DIR = ROOT / "firmware" / "native" / "user_c_modules" / "openbricks"

# On purpose: _C_API plugs the simulator's wheels into the cores in C (host only);
# interrupt_main and ticks_itself serve the hub's launcher and its self-ticking motor_process.
HOST_ONLY = {"_C_API"}
HUB_ONLY = {"interrupt_main", "ticks_itself"}
# The host's parsed frames are struct sequences with their own types; the hub's are attribute tuples
# with the same fields.
SCS_HOST_ONLY = {"Frame", "Status"}
TYPES = (
    "TrapezoidalProfile",
    "Observer",
    "MotorProcess",
    "Servo",
    "DriveBase",
    "ImuYaw",
    "SerialBus",
    "PCNTEncoder",
    "ICM45686",
    "HBridge",
)
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
