"""A stand-in for the esptool executable: records its arguments and prints esptool-like output.

Environment: FAKE_ESPTOOL_LOG (a file that gets one JSON argv list per call), FAKE_ESPTOOL_CHIP
("ESP32-S3" or "ESP32"), FAKE_ESPTOOL_STYLE ("v5": progress bars, "v4": "(NN %)" lines ending in \\r),
FAKE_ESPTOOL_FAIL (an esptool command name that fails like a board that won't connect),
FAKE_ESPTOOL_FAIL_PORT (a port where every command fails so), FAKE_ESPTOOL_WRITE_S (how long a write
takes, spread over its progress lines; a real one takes seconds).
"""

import json
import os
import sys
import time


def main(argv):
    with open(os.environ["FAKE_ESPTOOL_LOG"], "a", encoding="utf-8") as log:
        log.write(json.dumps(argv) + "\n")
    chip = os.environ.get("FAKE_ESPTOOL_CHIP", "ESP32-S3")
    style = os.environ.get("FAKE_ESPTOOL_STYLE", "v5")
    command = next(a for a in argv if not a.startswith("-") and a not in _option_values(argv))
    print("esptool v5.6.0")
    print("Connecting....")
    port = argv[argv.index("--port") + 1] if "--port" in argv else None
    if os.environ.get("FAKE_ESPTOOL_FAIL") == command or os.environ.get("FAKE_ESPTOOL_FAIL_PORT") == port:
        print("A fatal error occurred: Failed to connect to ESP32-S3: No serial data received.")
        return 2
    if style == "v5":
        print(f"Detecting chip type... {chip}")
        print(f"{'Chip type:':<20}{chip} (QFN56) (revision v0.2)")
    else:
        print(f"Chip is {chip} (revision v0.2)")
    if command == "write-flash":
        address = int(argv[-2], 16)
        size = os.path.getsize(argv[-1])
        pause = float(os.environ.get("FAKE_ESPTOOL_WRITE_S", "0")) / 10
        for step in range(0, 11):
            if step:
                sys.stdout.flush()
                time.sleep(pause)
            done = size * step // 10
            if style == "v5":
                bar = "=" * step
                print(
                    f"Writing at {address + done:#010x} [{bar:<10}] {10.0 * step:5.1f}% {done}/{size} bytes"
                )
            else:
                sys.stdout.write(f"Writing at {address + done:#010x}... ({step * 10} %)\r")
        print(f"\nWrote {size} bytes at {address:#010x} in 0.1 seconds.")
        print("Hash of data verified.")
        print("Hard resetting via RTS pin...")
    elif command == "erase-flash":
        print("Erasing flash memory (this may take a while)...")
        print("Flash memory erased successfully in 1.0 seconds.")
    return 0


def _option_values(argv):
    values = set()
    for i, arg in enumerate(argv[:-1]):
        if arg in ("--chip", "--port", "--baud", "-p", "-b", "-c"):
            values.add(argv[i + 1])
    return values


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
