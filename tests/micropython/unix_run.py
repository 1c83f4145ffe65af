"""Runs one runtime test file under the unix MicroPython built with the real `_openbricks_native`.

    echo '["test_a", "test_b"]' | build/micropython/micropython tests/micropython/unix_run.py MODULE

Run from the repository root by test_runtime_on_unix_micropython.py, one process per file (a
wedged test costs its file, not the run). It uses harness.py, the WebAssembly run's harness, so
both interpreters run a test the same way; each outcome is printed as one `@result {json}` line.
The test names come on stdin: the unix port turns each argument into a qstr, and one longer than
255 bytes stops the interpreter before the script starts.
"""

import json
import sys

sys.path[:0] = ["", "tests/openbricks", "tests/micropython"]

import harness  # noqa: E402 - after the path set-up; installs the fakes


def main():
    module, names_json = sys.argv[1], sys.stdin.read()
    loaded = json.loads(harness.load_tests(module, names_json))
    if not loaded["ok"]:
        print("@result " + json.dumps({"name": "<module>", "outcome": "failed", "error": loaded["error"]}))
        return
    for name in loaded["tests"]:
        result = json.loads(harness.run_test(name))
        result["name"] = name
        print("@result " + json.dumps(result))
    harness.unload_tests()


main()
