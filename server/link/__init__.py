"""Hub links: one async byte-stream interface over BLE, USB serial and virtual hubs, and the raw-REPL
client that speaks MicroPython's program channel over any of them.

Nothing here keeps process-wide state: the daemon owns many links at once, each its own object with
its own buffers, and transports are chosen per link (BLE backends are passed in, not patched in).
Transport modules import their libraries (bleak, pyserial) only when used.
"""

from openbricks_server.link.base import Link
from openbricks_server.link.errors import (
    HubCallError,
    HubException,
    HubNotFound,
    LinkClosed,
    LinkDropped,
    LinkError,
    LinkTimeout,
    ProtocolError,
    WriteRejected,
)

__all__ = [
    "HubCallError",
    "HubException",
    "HubNotFound",
    "Link",
    "LinkClosed",
    "LinkDropped",
    "LinkError",
    "LinkTimeout",
    "ProtocolError",
    "WriteRejected",
]
