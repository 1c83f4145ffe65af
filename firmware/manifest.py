# What an openbricks image freezes (MicroPython manifest; both boards' mpconfigboard.cmake point here).
# Relative paths are relative to this file; $(PORT_DIR) / $(MPY_DIR) come from the MicroPython build,
# and so do freeze/include/require/package/module, which the manifest tool puts in scope.
# ruff: noqa: F821

# The ESP32 port's own frozen modules: _boot.py mounts the filesystem, inisetup.py formats it on the
# first boot, flashbdev.py is its block device.
freeze("$(PORT_DIR)/modules")
include("$(MPY_DIR)/extmod/asyncio")

# The S3's status LED is a WS2812 (openbricks.hub.NeoPixelLED).
require("neopixel")

# The hub runtime, whole: every module a program or the host may import.
package("openbricks", base_path="..")

# What the hub does at power-up. Frozen boot.py / main.py win over files of the same name in the
# filesystem, so they look for a user's /boot.py or /main.py themselves.
module("boot.py", base_path="frozen")
module("main.py", base_path="frozen")
