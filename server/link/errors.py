"""What can go wrong on a hub link, as exception types a caller can tell apart.

Every message names the hub and what was being done, so a line in a log of twenty hubs is enough
to act on. `LinkError` is the root; the two kinds a caller usually handles differently are
`LinkTimeout` (the hub stayed silent: retry, or check that it runs) and `LinkDropped` (the
connection itself went away: reconnect).
"""

from __future__ import annotations


class LinkError(Exception):
    """Any failure of a hub link or of the protocol spoken over it."""


class LinkTimeout(LinkError, TimeoutError):
    """A wait ran out: the message says what was awaited, from which hub, for how long."""

    def __init__(self, what: str, hub: str, timeout_s: float):
        super().__init__(f"waiting for {what} from {hub} after {timeout_s:g} s")
        self.what = what
        self.hub = hub
        self.timeout_s = timeout_s


class LinkDropped(LinkError, ConnectionError):
    """The connection to the hub went away while it was in use (not closed by us)."""

    def __init__(self, hub: str, reason: str, during: str | None = None):
        where = f" while {during}" if during else ""
        super().__init__(f"link to {hub} dropped{where}: {reason}")
        self.hub = hub
        self.reason = reason
        self.during = during


class LinkClosed(LinkError):
    """The link was closed by this side and is used again."""

    def __init__(self, hub: str):
        super().__init__(f"link to {hub} is closed: connect it again before using it")
        self.hub = hub


class HubNotFound(LinkError):
    """No hub of that name answered a scan or a port lookup."""


class WriteRejected(LinkError):
    """The transport refused a write (for BLE: the packet was larger than the link allows)."""


class ProtocolError(LinkError):
    """The hub answered something the raw-REPL protocol does not allow at that point."""


class HubException(LinkError):
    """Code run on the hub raised; the message carries the hub's traceback."""

    def __init__(self, hub: str, traceback: str, stdout: bytes = b"", results: list | None = None):
        last = traceback.strip().splitlines()[-1].strip() if traceback.strip() else "unknown error"
        super().__init__(f"{hub} raised {last}\n{traceback.rstrip()}")
        self.hub = hub
        self.traceback = traceback
        #: The exception line alone ("MemoryError: memory allocation failed, ..."), for one-line reports.
        self.summary = last
        self.stdout = stdout
        #: Host-call result lines the code printed before it raised.
        self.results = results or []


class HubCallError(LinkError):
    """A host call on the hub reported failure (`"ok": false`): its reason is in the message."""

    def __init__(self, hub: str, call: str, error_type: str, error: str):
        super().__init__(f"{call} on {hub} failed ({error_type}): {error}")
        self.hub = hub
        self.call = call
        self.error_type = error_type
        self.error = error
