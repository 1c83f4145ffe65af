"""`openbricks list`: the virtual hubs on this computer and the Bluetooth devices in range.

Virtual hubs come first (marked "virtual"); then Bluetooth devices, strongest signal first, hubs
(those offering the Nordic UART Service) marked "hub". Devices without a name are shown only with
--all, under a placeholder. No Bluetooth adapter is not an error: the virtual hubs still list.
"""

from __future__ import annotations

import asyncio
import sys

from openbricks_server.errors import EXIT_OK

NO_NAME = "(no name)"


async def _ble_devices(timeout_s: float) -> list[tuple[str | None, str, int, bool]]:
    from bleak import BleakScanner

    from openbricks_server.link.ble import NUS_SERVICE_UUID

    found = await BleakScanner.discover(timeout=timeout_s, return_adv=True)
    devices = []
    for device, advert in found.values():
        is_hub = NUS_SERVICE_UUID in [uuid.lower() for uuid in advert.service_uuids]
        devices.append((advert.local_name or device.name, device.address, advert.rssi, is_hub))
    return sorted(devices, key=lambda d: d[2], reverse=True)


def main(args) -> int:
    from openbricks_server import console_client

    console = console_client.running()
    if console is not None:  # the console lists its hubs (virtual ones included) and what it scans
        return console_client.list_hubs(console, args)
    from openbricks_server.hub_table import HubRow, print_hubs
    from openbricks_server.link.discovery import virtual_hubs

    rows = []
    for hub in virtual_hubs():
        rows.append(HubRow(hub.name, "virtual", hub.pty, "running a program" if hub.running else "idle"))
    try:
        devices = asyncio.run(_ble_devices(args.timeout))
    except Exception as exc:  # noqa: BLE001 - no adapter / no D-Bus / radio off: all mean "no scan"
        from openbricks_server.hub_session import bluetooth_unavailable

        print(
            f"Bluetooth is unavailable on this computer ({bluetooth_unavailable(exc)}); listing virtual "
            "hubs only",
            file=sys.stderr,
        )
        devices = []
    for name, address, rssi, is_hub in devices:
        if name or args.all:
            rows.append(HubRow(name or NO_NAME, "hub" if is_hub else "ble", address, f"{rssi} dBm"))
    none_found = f"no hubs found (Bluetooth scan of {args.timeout:g} s; no virtual hubs running)"
    print_hubs(rows, args.json, none_found)
    return EXIT_OK
