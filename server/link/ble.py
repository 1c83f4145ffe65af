"""The BLE link: a hub's REPL over the Nordic UART Service, through bleak.

- Finding hubs: `scan()` lists hubs advertising the NUS service (openbricks puts the 128-bit UUID in
  its scan response, so scans are active), strongest signal first; `find_hub(name)` stops as soon
  as the flashed name is seen.
- Connecting goes through bleak-retry-connector's `establish_connection`, which retries the
  transient failures radios produce (aborted connections, busy adapters) with the right back-off.
- Writing: host -> hub bytes go to the RX characteristic as writes without response, cut to the
  characteristic's `max_write_without_response_size` (MTU - 3: 244 bytes at the hub's MTU of 247),
  re-read per write because the MTU can change after connecting. The OS queues them; bleak's await
  returns when there is room, which is the link's back-pressure.
- Reading: TX notifications feed the link's buffer in arrival order.
- Disconnects: bleak's disconnected callback marks the link dropped at once (the OS notices a
  dead link after the connection supervision timeout, typically well under 2 s); `reconnect()`
  connects to the same device again, and what the hub printed meanwhile (it keeps it) follows.

The bleak backend is a parameter (`client_backend`, `scanner_backend`): None picks the OS's, tests
pass an emulated radio's. bleak is imported when a BLE link is made, not with this package.
"""

from __future__ import annotations

import asyncio
from dataclasses import dataclass, field
from typing import Any

from openbricks_server.link.base import Link
from openbricks_server.link.errors import HubNotFound, LinkDropped, LinkError, WriteRejected

NUS_SERVICE_UUID = "6e400001-b5a3-f393-e0a9-e50e24dcca9e"
NUS_RX_UUID = "6e400002-b5a3-f393-e0a9-e50e24dcca9e"  # host writes (hub REPL input)
NUS_TX_UUID = "6e400003-b5a3-f393-e0a9-e50e24dcca9e"  # hub notifies (hub REPL output)

DEFAULT_SCAN_TIMEOUT_S = 5.0
DEFAULT_CONNECT_ATTEMPTS = 3


@dataclass(frozen=True)
class HubAdvert:
    """A hub seen on the air: its advertised name, address and signal strength."""

    name: str
    address: str
    rssi: int
    device: Any = field(compare=False, repr=False)  # bleak's BLEDevice, to connect without a rescan


def _advertises_nus(advertisement) -> bool:
    return NUS_SERVICE_UUID in [uuid.lower() for uuid in advertisement.service_uuids]


async def scan(
    timeout_s: float = DEFAULT_SCAN_TIMEOUT_S, *, scanner_backend: type | None = None
) -> list[HubAdvert]:
    """Hubs advertising the Nordic UART Service within `timeout_s`, strongest signal first."""
    from bleak import BleakScanner

    found: dict[str, HubAdvert] = {}

    def seen(device, advertisement) -> None:
        if _advertises_nus(advertisement):
            name = advertisement.local_name or device.name or device.address
            found[device.address] = HubAdvert(name, device.address, advertisement.rssi, device)

    async with BleakScanner(seen, service_uuids=[NUS_SERVICE_UUID], **_backend(scanner_backend)):
        await asyncio.sleep(timeout_s)
    return sorted(found.values(), key=lambda hub: hub.rssi, reverse=True)


async def find_hub(
    name: str, timeout_s: float = DEFAULT_SCAN_TIMEOUT_S, *, scanner_backend: type | None = None
) -> HubAdvert:
    """The hub advertising `name`, as soon as it is seen; HubNotFound (listing the others) if not."""
    from bleak import BleakScanner

    seen_hubs: dict[str, HubAdvert] = {}
    match = asyncio.get_running_loop().create_future()

    def seen(device, advertisement) -> None:
        if not _advertises_nus(advertisement):
            return
        advert_name = advertisement.local_name or device.name or device.address
        hub = HubAdvert(advert_name, device.address, advertisement.rssi, device)
        seen_hubs[device.address] = hub
        if advert_name == name and not match.done():
            match.set_result(hub)

    async with BleakScanner(seen, service_uuids=[NUS_SERVICE_UUID], **_backend(scanner_backend)):
        try:
            async with asyncio.timeout(timeout_s):
                return await match
        except TimeoutError:
            pass
    others = ", ".join(
        f"{hub.name} ({hub.rssi} dBm)" for hub in sorted(seen_hubs.values(), key=lambda h: -h.rssi)
    )
    raise HubNotFound(
        f"no hub named {name!r} advertised within {timeout_s:g} s "
        f"(hubs seen: {others or 'none'}); check that it is powered, that its BLE is on (BLE button), "
        "and that no other computer is connected to it"
    )


def _backend(backend: type | None) -> dict:
    return {} if backend is None else {"backend": backend}


class BleLink(Link):
    """The REPL of the hub advertising `name`, over BLE."""

    can_reconnect = True

    def __init__(
        self,
        name: str,
        *,
        device: Any = None,
        scan_timeout_s: float = DEFAULT_SCAN_TIMEOUT_S,
        connect_attempts: int = DEFAULT_CONNECT_ATTEMPTS,
        client_backend: type | None = None,
        scanner_backend: type | None = None,
        **kwargs: Any,
    ):
        super().__init__(name, **kwargs)
        self.device = device
        self.scan_timeout_s = scan_timeout_s
        self.connect_attempts = connect_attempts
        self._client_backend = client_backend
        self._scanner_backend = scanner_backend
        self._client = None
        self._rx_char = None

    def _describe(self) -> str:
        address = getattr(self.device, "address", None)
        return f"BLE {address}" if address else "BLE, by advertised name"

    @property
    def write_size(self) -> int:
        """Largest write the link takes in one packet now (MTU - 3)."""
        if self._rx_char is None:
            raise LinkError(f"{self.hub}: not connected")
        return self._rx_char.max_write_without_response_size

    async def _open(self) -> None:
        from bleak import BleakClient
        from bleak_retry_connector import establish_connection

        if self.device is None:
            self.device = (
                await find_hub(self.hub, self.scan_timeout_s, scanner_backend=self._scanner_backend)
            ).device
        client = await establish_connection(
            BleakClient,
            self.device,
            self.hub,
            disconnected_callback=self._on_disconnect,
            max_attempts=self.connect_attempts,
            **_backend(self._client_backend),
        )
        try:
            rx = client.services.get_characteristic(NUS_RX_UUID)
            tx = client.services.get_characteristic(NUS_TX_UUID)
            if rx is None or tx is None:
                raise LinkError(
                    f"{self.hub} has no Nordic UART Service: is it an openbricks hub with its REPL on BLE?"
                )
            self._client = client
            self._rx_char = rx
            await client.start_notify(tx, self._on_notify)
        except BaseException:
            self._client = None
            await client.disconnect()
            raise

    def _on_notify(self, _characteristic, data: bytearray) -> None:
        self._received(bytes(data))

    def _on_disconnect(self, client) -> None:
        if client is self._client:
            self._dropped(
                "the hub disconnected (out of range, powered off, reset, or taken by another computer)"
            )

    async def _send(self, data: bytes) -> None:
        from bleak.exc import BleakError

        client, rx = self._client, self._rx_char
        view = memoryview(data)
        sent = 0
        while sent < len(view):
            size = rx.max_write_without_response_size
            chunk = view[sent : sent + size]
            try:
                await client.write_gatt_char(rx, chunk, response=False)
            except BleakError as err:
                if not client.is_connected:
                    raise LinkDropped(
                        self.hub, str(err), f"sending ({sent} of {len(data)} bytes sent)"
                    ) from None
                raise WriteRejected(f"{self.hub} refused a {len(chunk)}-byte write: {err}") from None
            sent += len(chunk)

    async def _close(self) -> None:
        client, self._client = self._client, None
        if client is not None:
            await client.disconnect()
