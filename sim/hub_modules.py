"""The modules code on an openbricks hub can import: MicroPython's ESP32 port as firmware/ builds it.

One definition for two checks: tests/test_runtime_imports.py holds the hub runtime (`openbricks/`,
the frozen boot.py and main.py) to it, from the source; the simulator's hub Python
(virtual_hub/hub_python.py) refuses every other import from a program, as the hub itself would
(`ImportError: no module named 'subprocess'`).
"""

# Built into MicroPython's ESP32 port (MicroPython library docs, "ESP32 quick reference").
HUB_MODULES = frozenset({
    # the board, the radio and the firmware's own C module of control cores
    "machine", "esp", "esp32", "bluetooth", "_openbricks_native", "micropython",
    # the interpreter's built-in modules
    "builtins", "sys", "gc", "time", "struct", "os", "vfs", "math", "cmath", "array", "select", "io",
    "json", "errno", "binascii", "deflate", "collections", "random", "re", "hashlib", "heapq",
    "framebuf", "uctypes", "platform", "btree", "cryptolib",
    # frozen into the image by firmware/manifest.py
    "asyncio", "neopixel",
})  # fmt: skip

# The hub runtime, frozen into the image.
RUNTIME_PACKAGE = "openbricks"

# On the port, but not in an openbricks image or not for the runtime: the reason is the message.
REFUSED = {
    "network": "WiFi is off in openbricks images (firmware/boards/sdkconfig.nowifi); the host talks over BLE",
    "socket": "WiFi is off in openbricks images; the host talks over BLE",
    "ssl": "WiFi is off in openbricks images; the host talks over BLE",
    "espnow": "WiFi and ESP-NOW are off in openbricks images",
    "webrepl": "WiFi is off in openbricks images; the REPL reaches the host over BLE or USB",
    "_thread": "the runtime is single-threaded: periodic work runs in machine.Timer callbacks",
    "openbricks_native": "that is the host build of the control cores; on the hub it is `_openbricks_native`",
    "openbricks_sim": "the simulator is host code; the runtime must not depend on it",
    "openbricks_server": "the CLI and daemon are host code; the runtime must not depend on them",
}


def hub_name(name):
    """The hub module a program's `import NAME` reaches (the top-level name; a deprecated `u` prefix,
    `utime`, still reaches `time` as on the port), or None when the hub has no such module."""
    top = name.partition(".")[0]
    if top in HUB_MODULES or top == RUNTIME_PACKAGE:
        return top
    if top.startswith("u") and top[1:] in HUB_MODULES:
        return top[1:]
    return None
