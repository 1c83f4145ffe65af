"""Where another computer reaches this console: the addresses its share links are made of.

The console answers only to the host names it was started with (Host header check, auth.py), so a link
is only offered for an address it answers to; for the others the page says how to start it for the room.
"""

from __future__ import annotations

import ipaddress
import socket

from openbricks_server.daemon.config import DaemonConfig, is_loopback_host

# A documentation address (TEST-NET-1): connecting a UDP socket to it sends nothing, but makes the OS
# pick the interface that would carry traffic to the network, whose address is the one others use.
_PROBE = ("192.0.2.1", 9)


def lan_addresses() -> list[str]:
    """This computer's IPv4 addresses on its networks (not loopback), the outbound one first."""
    found: list[str] = []
    try:
        with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as probe:
            probe.connect(_PROBE)
            found.append(probe.getsockname()[0])
    except OSError:
        pass  # no route to any network
    try:
        infos = socket.getaddrinfo(socket.gethostname(), None, socket.AF_INET)
    except OSError:
        infos = []
    found += [info[4][0] for info in infos]
    out: list[str] = []
    for address in found:
        if address not in out and not ipaddress.ip_address(address).is_loopback:
            out.append(address)
    return out


def base_url(host: str, port: int) -> str:
    return f"http://[{host}]:{port}" if ":" in host else f"http://{host}:{port}"


def share_bases(config: DaemonConfig, lan: list[str]) -> list[str]:
    """The addresses another computer can open, as base URLs: none while the console listens on this
    computer only; else its own address (or, on every address, those of `lan` it answers to) and the
    --allow-host names."""
    if config.is_loopback:
        return []
    names: list[str] = []
    if config.host not in ("0.0.0.0", "::", ""):
        names.append(config.host.strip("[]"))
    else:
        names += [a for a in lan if a in config.host_names]
    names += [h for h in config.allowed_hosts if not is_loopback_host(h)]
    unique = list(dict.fromkeys(n.lower() for n in names))
    return [base_url(name, config.port) for name in unique]


def room_command(config: DaemonConfig, lan: list[str]) -> str:
    """How to start this console so that the room reaches it, with this computer's address filled in."""
    name = lan[0] if lan else "THIS-COMPUTERS-ADDRESS"
    port = "" if config.port == 8765 else f" --port {config.port}"
    return f"openbricks console --host 0.0.0.0 --allow-host {name}{port}"
