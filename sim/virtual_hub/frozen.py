"""The virtual hub's frozen boot.py and main.py: the firmware's (firmware/frozen/) one-liners, which
hand over to the runtime's openbricks.power_up, so a virtual hub powers up as a flashed one does.

They run as hub code in the REPL's namespace, under their frozen names. The firmware tree is not
installed with the Python package; what they do lives in the runtime, which is.
"""

BOOT_PY = "from openbricks import power_up\npower_up.boot(globals())\n"
MAIN_PY = "from openbricks import power_up\npower_up.main(globals())\n"
