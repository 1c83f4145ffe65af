"""The hub's hardware as the simulator models it (sim/shim): the one model these fixtures build on.

CPython imports it from the installed simulator; the MicroPython runs put `sim/` on the path
(tests/micropython/harness.py) and import it as `shim`, since the simulator package around it is
CPython's.
"""

import sys

if sys.implementation.name == "micropython":
    from shim import bluetooth, board, esp32, machine, mptime, neopixel, virtual_clock
else:
    from openbricks_sim.shim import bluetooth, board, esp32, machine, mptime, neopixel, virtual_clock

__all__ = ("bluetooth", "board", "esp32", "machine", "mptime", "neopixel", "virtual_clock")
