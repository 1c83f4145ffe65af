"""This machine's IPv4 TCP sockets as /proc/net/tcp lists them: who listens where, and how many are
connected to a server, for the tests and the benchmark of the sim view's forwarding."""

from __future__ import annotations

from pathlib import Path

_ESTABLISHED = "01"
_LISTEN = "0A"


def _sockets():
    """(local address, local port, state) of every IPv4 TCP socket."""
    for line in Path("/proc/net/tcp").read_text().splitlines()[1:]:
        local, _remote, state = line.split()[1:4]
        address, port_hex = local.split(":")
        yield ".".join(str(b) for b in reversed(bytes.fromhex(address))), int(port_hex, 16), state


def connections_to(port: int) -> int:
    """Established TCP connections whose server end is `port` (the sim view listens on 127.0.0.1 only)."""
    return sum(1 for _, local_port, state in _sockets() if local_port == port and state == _ESTABLISHED)


def listening_addresses(port: int) -> set[str]:
    """Local addresses of the sockets listening on `port`."""
    return {address for address, local_port, state in _sockets() if local_port == port and state == _LISTEN}
