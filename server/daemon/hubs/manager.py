"""The registry of hub actors: the virtual hubs the daemon starts, hubs found on a BLE scan, virtual
hubs already running on this computer, and USB-serial hubs; lookup by stable id or current name;
stop-all.

The embedded default starts N virtual hubs (`SimHub-1` ...) as subprocesses with the configured
world and connects them; closing the manager hands every hub back to its launcher and stops the
processes it started. The BLE scan runs in the background; on a computer without Bluetooth (no
adapter, no D-Bus) it says so in `ble_status` and the rest works on; `--no-ble` skips it. BLE hubs
are listed as they are seen and connected on request (a competition hall is full of other teams'
hubs), then kept connected until disconnected.
"""

from __future__ import annotations

import asyncio
import contextlib
import logging
from pathlib import Path
from typing import Any

from openbricks_server.daemon.hub_events import HubEvents
from openbricks_server.daemon.hubs.actor import HubActor
from openbricks_server.daemon.hubs.backend import (
    BleBackend,
    HubBackend,
    SerialBackend,
    VirtualBackend,
    hub_id,
    port_slug,
    start_virtual_hub,
)
from openbricks_server.daemon.hubs.errors import HubNotFoundError
from openbricks_server.link.errors import LinkError

log = logging.getLogger(__name__)

SCAN_S = 4.0
SCAN_PAUSE_S = 6.0
BLE_RETRY_S = 60.0
VIRTUAL_PREFIX = "SimHub-"


def _option(config: Any, name: str, default: Any) -> Any:
    return getattr(config, name, default)


class HubManager:
    def __init__(
        self,
        config: Any,
        hub_events: HubEvents,
        store: Any = None,
        *,
        ble_client_backend: type | None = None,
        ble_scanner_backend: type | None = None,
    ):
        self.config = config
        self.events = hub_events
        self.store = store
        self.ble_client_backend = ble_client_backend
        self.ble_scanner_backend = ble_scanner_backend
        self.ble_status = "not started"
        self.scan_s = SCAN_S
        self.scan_pause_s = SCAN_PAUSE_S
        self._actors: dict[str, HubActor] = {}
        self._tasks: list[asyncio.Task] = []

    # -- lifecycle ----------------------------------------------------------------------------------

    async def start(self) -> None:
        count = int(_option(self.config, "virtual", 0) or 0)
        if count:
            await self._start_virtual_hubs(count)
        for port in _option(self.config, "serial_ports", ()) or ():
            self.add(SerialBackend(port_slug(port), port), auto_connect=True)
        if not _option(self.config, "ble", True):
            self.ble_status = "off (--no-ble)"
        else:
            self.ble_status = "starting"
            self._tasks.append(asyncio.create_task(self._scan_ble(), name="ble scan"))
        self._tasks.append(asyncio.create_task(self._find_local_virtual_hubs(), name="virtual hubs"))

    async def close(self) -> None:
        for task in self._tasks:
            task.cancel()
        await asyncio.gather(*self._tasks, return_exceptions=True)
        self._tasks.clear()
        await asyncio.gather(*(actor.close() for actor in self._actors.values()), return_exceptions=True)

    async def _start_virtual_hubs(self, count: int) -> None:
        data_dir = _option(self.config, "resolved_data_dir", None) or _option(self.config, "data_dir", None)
        if data_dir is None:
            from openbricks_server.paths import data_dir as default_data_dir

            data_dir = default_data_dir()
        world = _option(self.config, "world", None)
        names = [f"{VIRTUAL_PREFIX}{i}" for i in range(1, count + 1)]
        started = await asyncio.gather(
            *(
                start_virtual_hub(
                    name,
                    hub_dir=str(Path(data_dir) / "virtual-hubs" / name),
                    world=world,
                    data_dir=str(data_dir),
                )
                for name in names
            ),
            return_exceptions=True,
        )
        for name, backend in zip(names, started, strict=True):
            if isinstance(backend, BaseException):
                log.error("virtual hub %s did not start: %s", name, backend)
                continue
            self.add(backend, auto_connect=True)

    def add(self, backend: HubBackend, *, auto_connect: bool = False) -> HubActor:
        actor = HubActor(backend, self.events, auto_connect=auto_connect)
        self._actors[actor.hub_id] = actor
        actor.start()
        return actor

    # -- lookup -------------------------------------------------------------------------------------

    def list(self) -> list[HubActor]:
        return sorted(self._actors.values(), key=lambda actor: (actor.state.kind != "virtual", actor.name))

    def get(self, ref: str) -> HubActor:
        """The hub with stable id `ref`, else the one currently named `ref`."""
        actor = self._actors.get(ref)
        if actor is not None:
            return actor
        named = [actor for actor in self._actors.values() if actor.name == ref]
        if len(named) == 1:
            return named[0]
        known = ", ".join(sorted(actor.name for actor in self._actors.values())) or "none"
        if named:
            ids = ", ".join(actor.hub_id for actor in named)
            raise HubNotFoundError(f"several hubs are named {ref!r}: {ids}", "address it by its id")
        raise HubNotFoundError(f"no hub {ref!r} (hubs: {known})", "use a hub's id or name from GET /api/hubs")

    # -- stop-all -----------------------------------------------------------------------------------

    async def stop_all(self, who: str) -> list[dict]:
        """Stop every connected hub at once; one report per hub, the unreachable ones included."""
        actors = self.list()
        results = await asyncio.gather(*(actor.stop(who) for actor in actors), return_exceptions=True)
        reports = []
        for actor, result in zip(actors, results, strict=True):
            if isinstance(result, BaseException):
                result = {"hub": actor.hub_id, "name": actor.name, "stopped": False, "detail": str(result)}
            reports.append(result)
        return reports

    # -- discovery ----------------------------------------------------------------------------------

    async def _scan_ble(self) -> None:
        from openbricks_server.link.ble import scan

        while True:
            try:
                adverts = await scan(self.scan_s, scanner_backend=self.ble_scanner_backend)
            except asyncio.CancelledError:
                raise
            except Exception as exc:  # noqa: BLE001 - no adapter, no D-Bus, radio off: all mean "no BLE"
                self.ble_status = (
                    f"unavailable ({type(exc).__name__}: {exc}); virtual and USB hubs work without it, "
                    "--no-ble skips the scan"
                )
                await asyncio.sleep(BLE_RETRY_S)
                continue
            self.ble_status = "scanning"
            for advert in adverts:
                key = hub_id("ble", advert.address)
                actor = self._actors.get(key)
                if actor is None:
                    backend = BleBackend(
                        advert.name, advert.address, advert.device, client_backend=self.ble_client_backend
                    )
                    actor = self.add(backend)
                else:
                    actor.backend.device = advert.device
                    actor.rename(advert.name)
                actor.seen(advert.rssi)
            await asyncio.sleep(self.scan_pause_s)

    async def _find_local_virtual_hubs(self) -> None:
        """Virtual hubs started by hand on this computer are listed too (connected on request)."""
        from openbricks_server.link.discovery import virtual_hubs

        while True:
            with contextlib.suppress(OSError, LinkError):
                for hub in await asyncio.to_thread(virtual_hubs):
                    if hub_id("virtual", hub.name) not in self._actors:
                        self.add(VirtualBackend(hub.name, hub.pty))
            await asyncio.sleep(SCAN_PAUSE_S)
