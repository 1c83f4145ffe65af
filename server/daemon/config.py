"""What `openbricks console` was started with: one frozen object every part of the daemon reads.

The defaults are the embedded console a fresh machine gets from `make console`: loopback only, two
virtual hubs with the simulator behind them, Bluetooth scanning on.
"""

from __future__ import annotations

import ipaddress
from dataclasses import dataclass
from pathlib import Path

DEFAULT_HOST = "127.0.0.1"
DEFAULT_PORT = 8765
DEFAULT_VIRTUAL_HUBS = 2
DEFAULT_FLASH_PARALLEL = 20  # esptool processes at once: each mostly waits on its USB port
DB_FILENAME = "console.sqlite3"
# Host header names that always reach a loopback bind; anything else is a DNS-rebinding attempt.
LOOPBACK_NAMES = frozenset({"localhost", "127.0.0.1", "::1"})


@dataclass(frozen=True)
class DaemonConfig:
    host: str = DEFAULT_HOST
    port: int = DEFAULT_PORT
    virtual: int = DEFAULT_VIRTUAL_HUBS  # virtual hubs started with the daemon (simulator behind each)
    world: str | None = None  # the virtual hubs' simulator world; None: the simulator's default
    data_dir: Path | None = None  # None: the user data dir (openbricks_server.paths.data_dir())
    ble: bool = True  # scan for and connect to Bluetooth hubs
    allowed_hosts: tuple[str, ...] = ()  # extra Host header names accepted (for a non-loopback bind)
    ring_size: int = 20_000  # events kept in memory for reconnecting clients
    client_queue: int = 2_000  # events buffered per WebSocket client before it is resynced from the store
    serial_ports: tuple[str, ...] = ()  # USB-serial hubs to hold (--serial PORT), connected at start
    flash_parallel: int = DEFAULT_FLASH_PARALLEL  # flash jobs run at once; more wait their turn
    flush_interval_s: float = 0.02  # output lines reach the database this long after they arrive (< 50 ms)

    @property
    def resolved_data_dir(self) -> Path:
        if self.data_dir is not None:
            return Path(self.data_dir).expanduser()
        from openbricks_server import paths

        return paths.data_dir()

    @property
    def db_path(self) -> Path:
        return self.resolved_data_dir / DB_FILENAME

    @property
    def is_loopback(self) -> bool:
        return is_loopback_host(self.host)

    @property
    def host_names(self) -> frozenset[str]:
        """Host header names (without port) this daemon answers to."""
        names = set(LOOPBACK_NAMES) | {h.lower() for h in self.allowed_hosts}
        if not _is_wildcard(self.host):
            names.add(self.host.lower().strip("[]"))
        return frozenset(names)

    def url(self, port: int | None = None) -> str:
        """The address a browser on this machine (or, for a non-loopback bind, the network) opens."""
        host = "127.0.0.1" if self.is_loopback or _is_wildcard(self.host) else self.host
        if ":" in host:
            host = f"[{host}]"
        return f"http://{host}:{self.port if port is None else port}"


def _is_wildcard(host: str) -> bool:
    return host in ("0.0.0.0", "::", "")


def is_loopback_host(host: str) -> bool:
    if host.lower() == "localhost":
        return True
    try:
        return ipaddress.ip_address(host.strip("[]")).is_loopback
    except ValueError:
        return False
