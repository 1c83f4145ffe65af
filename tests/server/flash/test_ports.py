"""A port is picked silently only when exactly one ESP board is connected."""

import pytest

from openbricks_server.errors import CliError
from openbricks_server.flash.ports import ESP_USB_VENDORS, SerialPort, pick_port

BOARD = SerialPort("/dev/ttyACM0", 0x303A, "USB JTAG/serial debug unit")
BRIDGE = SerialPort("/dev/ttyUSB0", 0x10C4, "CP2102 USB to UART")
MOUSE_DONGLE = SerialPort("/dev/ttyACM5", 0x046D, "Logitech receiver")
BUILTIN = SerialPort("/dev/ttyS0", None, "n/a")


def test_the_only_esp_device_is_picked_among_other_ports():
    assert pick_port([BUILTIN, MOUSE_DONGLE, BOARD], ESP_USB_VENDORS, "ESP32 board") == "/dev/ttyACM0"


def test_several_boards_are_listed_and_none_is_explained():
    with pytest.raises(
        CliError, match=r"2 ESP32 boards are connected \(/dev/ttyACM0 .*/dev/ttyUSB0.*pass --port"
    ):
        pick_port([BOARD, BRIDGE], ESP_USB_VENDORS, "ESP32 board")
    with pytest.raises(CliError, match=r"no ESP32 board found on USB \(seen: /dev/ttyS0 .*\); plug it in"):
        pick_port([BUILTIN, MOUSE_DONGLE], ESP_USB_VENDORS, "ESP32 board")
