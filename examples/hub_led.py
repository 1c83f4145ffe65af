# SPDX-License-Identifier: MIT
"""The hub's own parts: colour the status LED and read the Bluetooth button.

ESP32S3DevkitHub is the ESP32-S3 DevKitC-1: its WS2812 status LED on GPIO 48 and the Bluetooth
button on GPIO 38. Built with bluetooth=False, the button is left to the program instead of
toggling Bluetooth. Colours are 0..255 per channel; the LED's brightness (0.2 by default) scales them.

Run with:
    openbricks run -n RobotA examples/hub_led.py
    openbricks sim run examples/hub_led.py
"""

from openbricks.hub import ESP32S3DevkitHub
from openbricks.tools import wait

hub = ESP32S3DevkitHub(bluetooth=False)

for name, colour in (("red", (255, 0, 0)), ("green", (0, 255, 0)), ("blue", (0, 0, 255))):
    hub.led.rgb(*colour)
    print("LED", name)
    wait(300)
hub.led.off()
print("button held:", hub.bluetooth_button.pressed())
