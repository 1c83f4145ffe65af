"""Build MicroPython's unix port with our user C module and check it behaves like the host binding.

    python firmware/check_micropython_binding.py ~/micropython     # or MICROPY_DIR=~/micropython
    python firmware/check_micropython_binding.py --host-only       # the smoke script on the host binding

Compiling the hub binding needs MicroPython's C sources (a checkout, v1.27 or newer, with
`make -C ports/unix submodules` done), which no package registry ships, so this check runs where a
checkout exists (a firmware developer's machine, a firmware CI job) rather than in the test suite.
It builds mpy-cross and the unix port with USER_C_MODULES pointing at firmware/native/user_c_modules,
runs binding_smoke.py in that interpreter and under the host extension, and compares the numbers.
Exit status 0 means the hub binding compiled and agreed with the host to 1e-5.
"""

import json
import math
import os
import subprocess
import sys
import tempfile
from pathlib import Path

FIRMWARE = Path(__file__).resolve().parent
USER_C_MODULES = FIRMWARE / "native" / "user_c_modules"
SMOKE = FIRMWARE / "binding_smoke.py"


def checkout_from(argv):
    path = argv[1] if len(argv) > 1 else os.environ.get("MICROPY_DIR")
    if not path:
        sys.exit("give the MicroPython checkout as the first argument or in MICROPY_DIR")
    checkout = Path(path).expanduser()
    if not (checkout / "py" / "mpconfig.h").is_file() or not (checkout / "ports" / "unix").is_dir():
        sys.exit(f"{checkout} is not a MicroPython checkout (no py/mpconfig.h or ports/unix)")
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
            f"USER_C_MODULES={USER_C_MODULES}",
            "MICROPY_PY_FFI=0",
            "MICROPY_PY_SSL=0",
            "MICROPY_PY_BTREE=0",
        ],
    ]
    for step in steps:
        result = subprocess.run(step, capture_output=True, text=True, timeout=1200)
        if result.returncode != 0:
            sys.exit(f"{' '.join(step)} failed:\n{(result.stdout + result.stderr)[-6000:]}")
    return build_dir / "micropython"


def smoke_values(command):
    result = subprocess.run(command, capture_output=True, text=True, timeout=120)
    if result.returncode != 0 or not result.stdout.rstrip().endswith("SMOKE OK"):
        sys.exit(f"{' '.join(command)} failed:\n{result.stdout}{result.stderr}")
    return json.loads(result.stdout.splitlines()[-2])


def host_command():
    script = (
        "import sys, openbricks_native\n"
        "sys.modules['_openbricks_native'] = openbricks_native\n"
        f"source = open({str(SMOKE)!r}).read()\n"
        "exec(compile(source, 'binding_smoke.py', 'exec'), {'__name__': '__main__'})\n"
    )
    return [sys.executable, "-c", script]


def main(argv):
    if argv[1:] == ["--host-only"]:
        print(f"the smoke script passes on the host binding ({len(smoke_values(host_command()))} values)")
        return
    checkout = checkout_from(argv)
    with tempfile.TemporaryDirectory(prefix="ob-mpy-build-") as tmp:
        interpreter = build_unix_micropython(checkout, Path(tmp) / "build")
        hub = smoke_values([str(interpreter), str(SMOKE)])
    host = smoke_values(host_command())
    if hub.keys() != host.keys():
        sys.exit(f"the smoke script reported different values: hub {sorted(hub)}, host {sorted(host)}")
    off = [k for k, v in host.items() if not math.isclose(hub[k], v, rel_tol=1e-5, abs_tol=1e-4)]
    if off:
        detail = ", ".join(f"{k} ({hub[k]} vs {host[k]})" for k in off)
        sys.exit(f"the hub binding disagrees with the host on: {detail}")
    print(f"the MicroPython binding builds and matches the host on {len(host)} values")


if __name__ == "__main__":
    main(sys.argv)
