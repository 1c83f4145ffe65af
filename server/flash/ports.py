"""Finding the serial port of an ESP board (or a servo adapter) by its USB vendor id.

Picking a port silently is only safe when exactly one candidate is connected; with none or several the
user is told what was seen and asked for --port.
"""

from __future__ import annotations

import os
from dataclasses import dataclass

from openbricks_server.errors import CliError

# USB vendor ids of the chips that put ESP32 boards on USB.
ESP_USB_VENDORS = {
    0x303A: "Espressif USB",
    0x10C4: "Silicon Labs CP210x",
    0x1A86: "WCH CH340",
    0x0403: "FTDI",
}


@dataclass(frozen=True)
class SerialPort:
    device: str
    vid: int | None
    description: str
    pid: int | None = None

    @property
    def bridge(self) -> str | None:
        """What puts an ESP32 board on this port (Espressif USB, CP210x ...), if it is such a chip."""
        return ESP_USB_VENDORS.get(self.vid) if self.vid is not None else None


def connected_ports() -> list[SerialPort]:
    from serial.tools import list_ports

    return [SerialPort(p.device, p.vid, p.description or "", p.pid) for p in list_ports.comports()]


def pick_port(
    ports: list[SerialPort], vendors: dict[int, str] | None, what: str, option: str = "--port"
) -> str:
    """The one port whose vendor is in `vendors` (any USB port if None), or a CliError naming them all."""
    usb = [p for p in ports if p.vid is not None]
    candidates = [p for p in usb if vendors is None or p.vid in vendors]
    if len(candidates) == 1:
        return candidates[0].device
    if not candidates:
        seen = ", ".join(f"{p.device} ({p.description})" for p in ports) or "no serial ports at all"
        raise CliError(
            f"no {what} found on USB (seen: {seen}); plug it in with a data cable, or pass {option} PORT"
        )
    listed = ", ".join(
        f"{p.device} ({vendors.get(p.vid, p.description) if vendors else p.description})" for p in candidates
    )
    raise CliError(f"{len(candidates)} {what}s are connected ({listed}): pass {option} to choose one")


def find_esp_port() -> str:
    return pick_port(connected_ports(), ESP_USB_VENDORS, "ESP32 board")


def missing_port(port: str) -> str | None:
    """Why `port` cannot be a serial port, checked without opening it: None when it may be one. Only
    POSIX ports are paths; COM5 is checked by opening it."""
    if os.name != "posix" or os.path.exists(port):
        return None
    usb = [p.device for p in connected_ports() if p.vid is not None]
    return f"there is no such port (USB serial ports here: {', '.join(usb) or 'none'})"


def port_problem(port: str, exc: Exception) -> str:
    """Why a serial port did not open, said plainly (pyserial's text repeats errno twice)."""
    missing = missing_port(port)
    if missing:
        return missing
    if isinstance(exc, PermissionError) or "permission" in str(exc).lower():
        return "permission denied; add your user to the group that owns it (dialout on Linux)"
    if "busy" in str(exc).lower():
        return "another program has it open; close it (a serial monitor?) and retry"
    return "it is not a serial port this computer can open; check the port name"
