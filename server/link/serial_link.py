"""The serial link: a hub's REPL on a USB serial port (or any tty, such as a virtual hub's pty).

pyserial is blocking, so each link runs one reader thread that hands what arrives to the event loop
(`call_soon_threadsafe`), and writes go through a worker thread so a full OS buffer never stalls the
loop. A read error or end of file (unplugged cable, hub reset re-enumerating its USB port, a pty
whose other end closed) is a drop; `reconnect()` opens the same port path again.

The port is opened without toggling DTR/RTS: on the ESP32 DevKits those lines drive EN and GPIO0
through the auto-reset circuit, and asserting them would reset the hub (or put it in its ROM
bootloader) every time the host connects.
"""

from __future__ import annotations

import asyncio
import threading
from typing import Any

from openbricks_server.link.base import Link
from openbricks_server.link.errors import HubNotFound, LinkDropped

DEFAULT_BAUDRATE = 115200
READ_POLL_S = 0.05
READ_MAX_BYTES = 4096

# USB vendor ids of the bridges on ESP32 boards: Espressif's native USB, Silicon Labs CP210x, WCH CH34x.
ESP32_USB_VIDS = (0x303A, 0x10C4, 0x1A86)


def serial_ports() -> list[str]:
    """Serial ports that look like ESP32 hubs (by USB vendor id), sorted by name."""
    from serial.tools import list_ports

    return sorted(port.device for port in list_ports.comports() if port.vid in ESP32_USB_VIDS)


class SerialLink(Link):
    """The REPL on serial port `port`; `hub` names it in messages (the port path if not given)."""

    can_reconnect = True

    def __init__(self, port: str, *, hub: str | None = None, baudrate: int = DEFAULT_BAUDRATE, **kwargs: Any):
        super().__init__(hub or port, **kwargs)
        self.port = port
        self.baudrate = baudrate
        self._serial = None
        self._reader: threading.Thread | None = None
        self._stop = threading.Event()

    def _describe(self) -> str:
        return f"serial port {self.port}"

    async def _open(self) -> None:
        import serial

        def open_port():
            port = serial.Serial()
            port.port = self.port
            port.baudrate = self.baudrate
            port.timeout = READ_POLL_S
            port.dtr = False  # set before open(): pyserial applies them as it opens, without a pulse
            port.rts = False
            port.open()
            return port

        try:
            self._serial = await asyncio.to_thread(open_port)
        except serial.SerialException as err:
            raise HubNotFound(f"cannot open {self.port} for {self.hub}: {err}") from None
        self._stop.clear()
        loop = asyncio.get_running_loop()
        self._reader = threading.Thread(
            target=self._read_loop, args=(self._serial, loop), name=f"serial-{self.port}", daemon=True
        )
        self._reader.start()

    def _read_loop(self, port, loop: asyncio.AbstractEventLoop) -> None:
        import serial

        while not self._stop.is_set():
            try:
                data = port.read(max(1, min(port.in_waiting, READ_MAX_BYTES)))
            except (serial.SerialException, OSError, TypeError, ValueError) as err:
                # TypeError/ValueError: pyserial's reaction to a port closed under it.
                if not self._stop.is_set():
                    loop.call_soon_threadsafe(self._dropped, f"{self.port}: {err}")
                return
            if data:
                loop.call_soon_threadsafe(self._received, data)

    async def _send(self, data: bytes) -> None:
        import serial

        port = self._serial
        try:
            await asyncio.to_thread(port.write, data)
        except (serial.SerialException, OSError) as err:
            self._dropped(f"{self.port}: {err}")
            raise LinkDropped(self.hub, str(err), f"sending {len(data)} bytes") from None

    async def _close(self) -> None:
        self._stop.set()
        reader, self._reader = self._reader, None
        if reader is not None:
            await asyncio.to_thread(reader.join, 1.0)
        port, self._serial = self._serial, None
        if port is not None:
            await asyncio.to_thread(port.close)
