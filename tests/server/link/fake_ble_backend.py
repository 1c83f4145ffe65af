"""A bleak backend for tests and benchmarks: emulated openbricks hubs on an emulated radio.

bleak chooses its OS backend per object, and `BleakClient(..., backend=cls)` / `BleakScanner(...,
backend=cls)` accept any `BaseBleakClient` / `BaseBleakScanner` subclass; everything above the
backend (BleakClient's characteristic resolution, write/notify plumbing, bleak-retry-connector's
`establish_connection` retry loop) is bleak's real code. A `FakeRadio` hands out backend classes
bound to it, so two tests (or four benchmark hubs) never share state through a module global.

What the emulation holds a host to, as a real link would:
- MTU: the ATT MTU is 247 (as the hub asks for), so a write without response carries at most 244
  bytes; a larger one is refused with a BleakError, never silently split.
- Connection events: every `interval_ms`, at most `packets_per_interval` packets go each way. A
  hub's reply to what it received in one event leaves at the next event at the earliest, so a
  request/response round trip costs two intervals, as on the air.
- Back-pressure: the host stack buffers `host_queue_packets` writes without response; beyond that
  `write_gatt_char` waits for room (as CoreBluetooth's canSendWriteWithoutResponse or BlueZ's
  AcquireWrite socket do).
- Ordering: notifications are delivered in the order the hub produced the bytes, one callback per
  packet, each at most MTU - 3 bytes.
- Disconnects: `drop()` (or a byte-count trigger, `drop_after_host_bytes`) kills the link on the
  air at once; the host learns of it after `supervision_timeout_ms` (writes meanwhile are lost),
  then bleak's disconnected callback runs. The hub side behaves like openbricks.ble_repl: output
  made while no central listens is held (newest `hub_tx_buffer_bytes`) and sent once the next
  central writes or `connect_grace_ms` after it connects.
Behind each peripheral runs an emulated hub (`ScriptedHub`), so the bytes are real raw-REPL traffic.
"""

from __future__ import annotations

import asyncio
import itertools
from collections import deque
from dataclasses import dataclass, field
from typing import Any

from bleak.backends.characteristic import BleakGATTCharacteristic
from bleak.backends.client import BaseBleakClient, NotifyCallback
from bleak.backends.descriptor import BleakGATTDescriptor
from bleak.backends.device import BLEDevice
from bleak.backends.scanner import AdvertisementData, BaseBleakScanner
from bleak.backends.service import BleakGATTService, BleakGATTServiceCollection
from bleak.exc import BleakDeviceNotFoundError, BleakError

from tests.server.link.scripted_hub import ScriptedHub

NUS_SERVICE = "6e400001-b5a3-f393-e0a9-e50e24dcca9e"
NUS_RX = "6e400002-b5a3-f393-e0a9-e50e24dcca9e"
NUS_TX = "6e400003-b5a3-f393-e0a9-e50e24dcca9e"
ATT_HEADER_BYTES = 3
MAX_ATTRIBUTE_BYTES = 512


@dataclass
class LinkTiming:
    """The air between the host and one hub."""

    mtu: int = 247
    interval_ms: float = 7.5
    packets_per_interval: int = 4
    host_queue_packets: int = 16
    supervision_timeout_ms: float = 200.0
    connect_grace_ms: float = 1000.0
    hub_tx_buffer_bytes: int = 4096
    advertising_interval_ms: float = 100.0

    @property
    def payload_bytes(self) -> int:
        return self.mtu - ATT_HEADER_BYTES

    @property
    def capacity_bytes_per_s(self) -> float:
        """Payload one direction can carry: full packets in every connection event."""
        return self.payload_bytes * self.packets_per_interval / (self.interval_ms / 1000)


@dataclass
class LinkStats:
    writes: int = 0
    host_bytes: int = 0
    largest_write: int = 0
    notifications: int = 0
    hub_bytes: int = 0
    refused_writes: int = 0
    lost_host_bytes: int = 0
    dropped_hub_bytes: int = 0
    events: int = 0


class FakeHubPeripheral:
    """One hub on the air: its advertisement, its NUS GATT server and the emulated hub behind it."""

    def __init__(
        self,
        hub: ScriptedHub,
        address: str,
        *,
        rssi: int = -60,
        timing: LinkTiming | None = None,
        advertises_nus: bool = True,
    ):
        self.hub = hub
        self.name = hub.name
        self.address = address
        self.rssi = rssi
        self.timing = timing or LinkTiming()
        self.advertises_nus = advertises_nus
        self.stats = LinkStats()
        self.connection: _Connection | None = None
        self.connections = 0
        #: Connection attempts to refuse (each with a transient BlueZ-style error) before accepting.
        self.refuse_connections = 0
        #: Cut the link once the host has sent this many bytes in the current connection.
        self.drop_after_host_bytes: int | None = None
        self._held = bytearray()  # hub output waiting for a listening central
        self._attached_loop: asyncio.AbstractEventLoop | None = None

    # -- the hub's output side (openbricks.ble_repl's TX ring, modelled) -------------------------

    def _attach(self, loop: asyncio.AbstractEventLoop) -> None:
        if self._attached_loop is not loop:
            self.hub.attach(self._hub_output, loop)
            self._attached_loop = loop

    def _hub_output(self, data: bytes) -> None:
        self._held += data
        overflow = len(self._held) - self.timing.hub_tx_buffer_bytes
        if overflow > 0:
            # The bridge keeps the newest output: what a reconnecting host needs to resume.
            del self._held[:overflow]
            self.stats.dropped_hub_bytes += overflow

    def _take_notification(self) -> bytes:
        size = self.timing.payload_bytes
        packet = bytes(self._held[:size])
        del self._held[:size]
        return packet

    @property
    def advertising(self) -> bool:
        return self.connection is None

    def drop(self, reason: str = "connection supervision timeout") -> None:
        """Kill the link on the air now (the host notices after the supervision timeout)."""
        if self.connection is not None:
            self.connection.lose(reason)


class FakeRadio:
    """The air shared by a test's hubs; gives bleak backend classes bound to it."""

    def __init__(self):
        self.peripherals: dict[str, FakeHubPeripheral] = {}
        self._serial = itertools.count(1)
        radio = self
        self.client_backend: type[FakeBleakClient] = type(
            "FakeBleakClient", (FakeBleakClient,), {"radio": radio}
        )
        self.scanner_backend: type[FakeBleakScanner] = type(
            "FakeBleakScanner", (FakeBleakScanner,), {"radio": radio}
        )

    def add_hub(self, hub: ScriptedHub, **kwargs) -> FakeHubPeripheral:
        n = next(self._serial)
        address = kwargs.pop("address", f"24:0A:C4:00:00:{n:02X}")
        peripheral = FakeHubPeripheral(hub, address, **kwargs)
        self.peripherals[address.upper()] = peripheral
        return peripheral

    def find(self, address: str) -> FakeHubPeripheral | None:
        return self.peripherals.get(address.upper())


class _Connection:
    """A live link: connection events pace both directions."""

    def __init__(self, peripheral: FakeHubPeripheral, client: FakeBleakClient):
        self.peripheral = peripheral
        self.client = client
        self.timing = peripheral.timing
        self.loop = asyncio.get_running_loop()
        self.up: deque[bytes] = deque()  # host -> hub packets waiting for a connection event
        self.room = asyncio.Event()
        self.room.set()
        self.on_air = True  # False once the link is lost on the air
        self.noticed = False  # True once the host knows
        self.notify: NotifyCallback | None = None
        self.listening = False
        self.connected_at = self.loop.time()
        self.host_bytes = 0
        self._task = self.loop.create_task(self._run_events())

    async def _run_events(self) -> None:
        interval = self.timing.interval_ms / 1000
        next_event = self.loop.time() + interval
        try:
            while self.on_air:
                delay = next_event - self.loop.time()
                if delay > 0:
                    await asyncio.sleep(delay)
                now = self.loop.time()
                due = 1 + int((now - next_event) / interval)  # events that happened while we slept
                next_event += due * interval
                self._event(due * self.timing.packets_per_interval)
        except asyncio.CancelledError:
            pass

    def _event(self, budget: int) -> None:
        peripheral = self.peripheral
        peripheral.stats.events += 1
        # Hub -> host first: only output the hub made before this event can go in it.
        if not self.listening and self.loop.time() - self.connected_at >= self.timing.connect_grace_ms / 1000:
            self.listening = True
        sent = 0
        while self.listening and self.notify is not None and peripheral._held and sent < budget:
            packet = peripheral._take_notification()
            peripheral.stats.notifications += 1
            peripheral.stats.hub_bytes += len(packet)
            self.notify(bytearray(packet))
            sent += 1
        # Host -> hub: the hub's answers to these wait for the next event.
        delivered = 0
        while self.up and delivered < budget and self.on_air:
            packet = self.up.popleft()
            delivered += 1
            self.listening = True  # a central that writes has subscribed (as the bridge assumes)
            peripheral.hub.feed(packet)
        if len(self.up) < self.timing.host_queue_packets:
            self.room.set()

    async def queue_write(self, data: bytes) -> None:
        while len(self.up) >= self.timing.host_queue_packets and self.on_air:
            self.room.clear()
            await self.room.wait()
        stats = self.peripheral.stats
        stats.writes += 1
        stats.host_bytes += len(data)
        stats.largest_write = max(stats.largest_write, len(data))
        if not self.on_air:
            stats.lost_host_bytes += len(data)  # the host does not know yet: the bytes vanish
            return
        self.host_bytes += len(data)
        limit = self.peripheral.drop_after_host_bytes
        if limit is not None and self.host_bytes >= limit:
            keep = len(data) - (self.host_bytes - limit)
            if keep > 0:
                self.up.append(data[:keep])
            self.peripheral.drop_after_host_bytes = None
            self.lose(f"connection supervision timeout (injected after {limit} host bytes)")
            return
        self.up.append(data)

    def lose(self, reason: str) -> None:
        """The radio link is gone: stop events now, tell the host after the supervision timeout."""
        if not self.on_air:
            return
        self.on_air = False
        self.room.set()
        self._task.cancel()
        self.up.clear()
        if self.peripheral.connection is self:
            self.peripheral.connection = None  # the hub advertises again at once
        self.loop.call_later(self.timing.supervision_timeout_ms / 1000, self.client._link_lost, self, reason)

    def close(self) -> None:
        """The host disconnects on purpose."""
        self.on_air = False
        self.noticed = True
        self.room.set()
        self._task.cancel()
        if self.peripheral.connection is self:
            self.peripheral.connection = None


class FakeBleakClient(BaseBleakClient):
    """The client backend; use `radio.client_backend` (a subclass bound to one radio)."""

    radio: FakeRadio

    def __init__(self, address_or_ble_device: BLEDevice | str, **kwargs: Any):
        super().__init__(
            address_or_ble_device,
            disconnected_callback=kwargs.pop("disconnected_callback", None),
            timeout=kwargs.pop("timeout", 10.0),
        )
        self._connection: _Connection | None = None
        self._name = address_or_ble_device.name if isinstance(address_or_ble_device, BLEDevice) else None
        self.connect_kwargs: list[dict] = []

    @property
    def name(self) -> str:
        return self._name or self.address

    @property
    def mtu_size(self) -> int:
        peripheral = self.radio.find(self.address)
        return peripheral.timing.mtu if peripheral else 23

    @property
    def is_connected(self) -> bool:
        return self._connection is not None and not self._connection.noticed

    async def connect(self, pair: bool, **kwargs: Any) -> None:
        self.connect_kwargs.append(dict(kwargs))
        peripheral = self.radio.find(self.address)
        if peripheral is None:
            raise BleakDeviceNotFoundError(self.address, f"Device with address {self.address} was not found.")
        await asyncio.sleep(2 * peripheral.timing.interval_ms / 1000)  # connection setup on the air
        if peripheral.refuse_connections > 0:
            peripheral.refuse_connections -= 1
            raise BleakError("le-connection-abort-by-local")
        if peripheral.connection is not None:
            raise BleakError(f"{peripheral.name} is connected to another central and does not advertise")
        peripheral._attach(asyncio.get_running_loop())
        connection = _Connection(peripheral, self)
        peripheral.connection = connection
        peripheral.connections += 1
        self._connection = connection
        self.services = self._nus_services(peripheral)

    def _nus_services(self, peripheral: FakeHubPeripheral) -> BleakGATTServiceCollection:
        services = BleakGATTServiceCollection()
        service = BleakGATTService(None, 0x10, NUS_SERVICE)
        services.add_service(service)
        size = lambda: peripheral.timing.payload_bytes  # noqa: E731 - bleak takes a callable
        services.add_characteristic(
            BleakGATTCharacteristic(None, 0x11, NUS_RX, ["write-without-response", "write"], size, service)
        )
        tx = BleakGATTCharacteristic(None, 0x13, NUS_TX, ["read", "notify"], size, service)
        services.add_characteristic(tx)
        return services

    def _link_lost(self, connection: _Connection, reason: str) -> None:
        if connection is not self._connection or connection.noticed:
            return
        connection.noticed = True
        if self._disconnected_callback is not None:
            self._disconnected_callback()

    async def disconnect(self) -> None:
        if self._connection is not None:
            self._connection.close()
        self._connection = None

    async def pair(self, *args: Any, **kwargs: Any) -> None:
        raise BleakError("openbricks hubs do not pair: connect without pairing")

    async def unpair(self) -> None:
        raise BleakError("openbricks hubs do not pair")

    def _live(self) -> _Connection:
        if self._connection is None or self._connection.noticed:
            raise BleakError("Not connected")
        return self._connection

    async def read_gatt_char(self, characteristic: BleakGATTCharacteristic, **kwargs: Any) -> bytearray:
        self._live()
        return bytearray()

    async def read_gatt_descriptor(self, descriptor: BleakGATTDescriptor, **kwargs: Any) -> bytearray:
        raise BleakError("the NUS characteristics have no readable descriptors here")

    async def write_gatt_char(self, characteristic: BleakGATTCharacteristic, data, response: bool) -> None:
        connection = self._live()
        if characteristic.uuid != NUS_RX:
            raise BleakError(f"characteristic {characteristic.uuid} is not writable")
        limit = MAX_ATTRIBUTE_BYTES if response else connection.timing.payload_bytes
        if len(data) > limit:
            connection.peripheral.stats.refused_writes += 1
            kind = "write request" if response else "write without response"
            raise BleakError(
                f"a {kind} of {len(data)} bytes exceeds the {limit}-byte limit at MTU {connection.timing.mtu}"
            )
        await connection.queue_write(bytes(data))

    async def write_gatt_descriptor(self, descriptor: BleakGATTDescriptor, data) -> None:
        raise BleakError("the NUS characteristics have no writable descriptors here")

    async def start_notify(
        self, characteristic: BleakGATTCharacteristic, callback: NotifyCallback, **kwargs
    ) -> None:
        connection = self._live()
        if characteristic.uuid != NUS_TX:
            raise BleakError(f"characteristic {characteristic.uuid} does not notify")
        connection.notify = callback

    async def stop_notify(self, characteristic: BleakGATTCharacteristic) -> None:
        if self._connection is not None:
            self._connection.notify = None


class FakeBleakScanner(BaseBleakScanner):
    """The scanner backend; use `radio.scanner_backend`. Advertising hubs are reported every
    advertising interval with their name, RSSI and (merged scan response) the NUS service UUID."""

    radio: FakeRadio

    def __init__(self, detection_callback, service_uuids, scanning_mode="active", **kwargs: Any):
        super().__init__(detection_callback, service_uuids)
        self._task: asyncio.Task | None = None
        self.scanning_mode = scanning_mode

    async def start(self) -> None:
        self.seen_devices = {}
        self._task = asyncio.get_running_loop().create_task(self._listen())

    async def stop(self) -> None:
        if self._task is not None:
            self._task.cancel()
            try:
                await self._task
            except asyncio.CancelledError:
                pass
            self._task = None

    async def _listen(self) -> None:
        interval = (
            min(p.timing.advertising_interval_ms for p in self.radio.peripherals.values()) / 1000
            if self.radio.peripherals
            else 0.1
        )
        while True:
            for peripheral in list(self.radio.peripherals.values()):
                if not peripheral.advertising:
                    continue
                uuids = [NUS_SERVICE] if peripheral.advertises_nus else []
                if not self.is_allowed_uuid(uuids):
                    continue
                advertisement = AdvertisementData(
                    local_name=peripheral.name,
                    manufacturer_data={},
                    service_data={},
                    service_uuids=uuids,
                    tx_power=None,
                    rssi=peripheral.rssi,
                    platform_data=(),
                )
                device = self.create_or_update_device(
                    peripheral.address, peripheral.address, peripheral.name, peripheral, advertisement
                )
                self.call_detection_callbacks(device, advertisement)
            await asyncio.sleep(interval)


@dataclass
class HubBench:
    """A radio with named hubs on it, ready for tests: `bench.radio`, `bench.hubs[name]`."""

    radio: FakeRadio = field(default_factory=FakeRadio)
    peripherals: dict[str, FakeHubPeripheral] = field(default_factory=dict)

    def add(
        self, name: str, *, rssi: int = -60, timing: LinkTiming | None = None, **hub_kwargs
    ) -> FakeHubPeripheral:
        peripheral = self.radio.add_hub(ScriptedHub(name, **hub_kwargs), rssi=rssi, timing=timing)
        self.peripherals[name] = peripheral
        return peripheral
