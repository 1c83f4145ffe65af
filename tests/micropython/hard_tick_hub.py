"""The hub as far as the unix port's hard-tick scripts need it (hard_tick_drive.py, hard_tick_sensors.py).

`machine.UART` is the emulated servo bus (`_openbricks_bench.BenchBus`, in C); nothing else of
`machine` is used on these paths (the firmware's own drivers own the ICM-45686's SPI and the PCNT
units). `busy()` is a program's Python that never sleeps and never calls the runtime.
"""

import sys
import time


def install_machine(bench):
    """Make `import machine` hand out `bench` as every UART."""

    class _Machine:
        Pin = SPI = Timer = None

        @staticmethod
        def UART(uart_id, **_wiring):
            return bench

    sys.modules["machine"] = _Machine


def busy(ms):
    """Spin in Python for `ms` without sleeping or touching the runtime; returns loop rounds."""
    start = time.ticks_ms()
    rounds = 0
    while time.ticks_diff(time.ticks_ms(), start) < ms:
        rounds += 1
    return rounds
