"""Build MicroPython's unix port with our user C module and check it computes what the host binding does.

    python firmware/check_micropython_binding.py SRC       # SRC: a source tarball or checkout
    python firmware/check_micropython_binding.py --host-only   # the smoke script on the host binding

It builds the interpreter with firmware/unix_micropython.py (into build/micropython, as `make
micropython` does), runs binding_smoke.py in it and under the host extension, and compares the
numbers. Exit status 0 means the hub binding compiled and agreed with the host to 1e-5.
`make test` runs the same comparison (tests/micropython/test_runtime_on_unix_micropython.py).
"""

import json
import math
import subprocess
import sys
from pathlib import Path

FIRMWARE = Path(__file__).resolve().parent
SMOKE = FIRMWARE / "binding_smoke.py"
BUILD_DIR = FIRMWARE.parent / "build" / "micropython"


def smoke_values(command):
    result = subprocess.run(command, capture_output=True, text=True, timeout=120)
    if result.returncode != 0 or not result.stdout.rstrip().endswith("SMOKE OK"):
        raise RuntimeError(f"{' '.join(command)} failed:\n{result.stdout}{result.stderr}")
    return json.loads(result.stdout.splitlines()[-2])


def host_command():
    script = (
        "import sys, openbricks_native\n"
        "sys.modules['_openbricks_native'] = openbricks_native\n"
        f"source = open({str(SMOKE)!r}).read()\n"
        "exec(compile(source, 'binding_smoke.py', 'exec'), {'__name__': '__main__'})\n"
    )
    return [sys.executable, "-c", script]


def disagreements(hub, host):
    """Names of the smoke values the two builds computed differently (numbers beyond 1e-5 relative,
    words at all)."""

    def close(a, b):
        if isinstance(b, list):
            return isinstance(a, list) and len(a) == len(b) and all(map(close, a, b))
        if isinstance(b, str):
            return a == b
        return math.isclose(a, b, rel_tol=1e-5, abs_tol=1e-4)

    if hub.keys() != host.keys():
        return sorted(set(hub) ^ set(host))
    return [k for k, v in host.items() if not close(hub[k], v)]


def main(argv):
    if argv[1:] == ["--host-only"]:
        print(f"the smoke script passes on the host binding ({len(smoke_values(host_command()))} values)")
        return
    if len(argv) != 2:
        sys.exit(__doc__)
    sys.path.insert(0, str(FIRMWARE))
    import unix_micropython

    try:
        interpreter = unix_micropython.build(argv[1], BUILD_DIR)
    except unix_micropython.BuildError as err:
        sys.exit(str(err))
    hub = smoke_values([str(interpreter), str(SMOKE)])
    host = smoke_values(host_command())
    off = disagreements(hub, host)
    if off:
        sys.exit("the hub binding disagrees with the host on: " + ", ".join(off))
    print(f"the MicroPython binding builds and matches the host on {len(host)} values")


if __name__ == "__main__":
    main(sys.argv)
