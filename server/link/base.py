"""The async interface every hub link implements: connect, write bytes, read what the hub sends, close.

A link is one byte stream to one hub, whatever carries it (BLE Nordic UART Service, a USB serial
port, a virtual hub's pipes or pty). Transports subclass `Link` and implement four hooks (`_open`,
`_send`, `_close`, and `_describe` for messages); they push what arrives with `_received(data)` and
report an unexpected loss with `_dropped(reason)`, both on the event loop's thread.

Rules the readers can rely on:
- Nothing received is ever lost to a drop: bytes already buffered are handed out first, and only a
  read that needs more than the buffer holds raises `LinkDropped`. The buffer also survives
  `reconnect()`, so output the hub sends after a reconnect continues where it stopped.
- Every wait has a timeout and names what it waited for (`LinkTimeout`).
- A drop is noticed when the transport reports it, not at the next read: `disconnected` is set,
  listeners added with `on_drop` are called at once, and blocked readers wake with `LinkDropped`.
- No state outside the object: the daemon holds many links in one loop.
"""

from __future__ import annotations

import asyncio
from collections.abc import AsyncIterator, Callable

from openbricks_server.link.errors import LinkClosed, LinkDropped, LinkError, LinkTimeout

DEFAULT_CONNECT_TIMEOUT_S = 20.0
DEFAULT_WRITE_TIMEOUT_S = 10.0


class Link:
    """One byte stream to one hub. Use as `async with link:` or call `connect()` / `close()`."""

    #: Whether `reconnect()` can bring the same hub back after a drop (BLE and serial can; a
    #: virtual hub behind pipes cannot: its process is gone with them).
    can_reconnect = False

    def __init__(
        self,
        hub: str,
        *,
        connect_timeout_s: float = DEFAULT_CONNECT_TIMEOUT_S,
        write_timeout_s: float = DEFAULT_WRITE_TIMEOUT_S,
    ):
        self.hub = hub
        self.connect_timeout_s = connect_timeout_s
        self.write_timeout_s = write_timeout_s
        self.bytes_sent = 0
        self.bytes_received = 0
        #: Set while the link is down (before connect, after a drop or a close).
        self.disconnected = asyncio.Event()
        self.disconnected.set()
        #: Loop time of the last unexpected drop (None if it never dropped).
        self.dropped_at: float | None = None
        self._rx = bytearray()
        self._rx_ready = asyncio.Event()
        self._state = "new"  # new -> open -> dropped/closed -> open (reconnect) ...
        self._drop_reason = ""
        self._drop_listeners: list[Callable[[LinkDropped], None]] = []

    # -- for transports -------------------------------------------------------------------------

    async def _open(self) -> None:
        raise NotImplementedError

    async def _send(self, data: bytes) -> None:
        raise NotImplementedError

    async def _close(self) -> None:
        raise NotImplementedError

    def _received(self, data: bytes) -> None:
        """Transports call this (on the loop's thread) with every piece of data, in arrival order."""
        if data:
            self._rx += data
            self.bytes_received += len(data)
            self._rx_ready.set()

    def _dropped(self, reason: str) -> None:
        """Transports call this (on the loop's thread) when the connection is lost unasked."""
        if self._state != "open":
            return
        self._state = "dropped"
        self._drop_reason = reason
        self.dropped_at = asyncio.get_running_loop().time()
        self.disconnected.set()
        self._rx_ready.set()  # wake a blocked reader so it raises now, not at its timeout
        drop = LinkDropped(self.hub, reason)
        for listener in list(self._drop_listeners):
            listener(drop)

    # -- state ------------------------------------------------------------------------------------

    @property
    def is_open(self) -> bool:
        return self._state == "open"

    def on_drop(self, listener: Callable[[LinkDropped], None]) -> Callable[[], None]:
        """Call `listener(LinkDropped)` as soon as the transport reports a drop; returns an unsubscribe."""
        self._drop_listeners.append(listener)
        return lambda: self._drop_listeners.remove(listener) if listener in self._drop_listeners else None

    def _check_usable(self, during: str) -> None:
        if self._state == "open":
            return
        if self._state == "dropped":
            raise LinkDropped(self.hub, self._drop_reason, during)
        raise LinkClosed(self.hub)

    # -- connecting ---------------------------------------------------------------------------------

    async def connect(self, timeout_s: float | None = None) -> None:
        if self._state == "open":
            return
        timeout_s = self.connect_timeout_s if timeout_s is None else timeout_s
        try:
            async with asyncio.timeout(timeout_s):
                await self._open()
        except TimeoutError:
            await self._close_quietly()
            raise LinkTimeout(f"a connection ({self._describe()})", self.hub, timeout_s) from None
        self._state = "open"
        self.disconnected.clear()

    async def reconnect(self, timeout_s: float | None = None) -> None:
        """Bring the link back after a drop; what was received before stays readable."""
        if not self.can_reconnect:
            raise LinkError(f"{self.hub}: a {type(self).__name__} cannot reconnect; open a new one")
        if self._state == "open":
            return
        await self._close_quietly()
        self._state = "reconnecting"
        await self.connect(timeout_s)

    async def close(self) -> None:
        """Close the link (idempotent); unread data stays readable, new reads raise LinkClosed."""
        if self._state == "closed":
            return
        self._state = "closed"
        self.disconnected.set()
        self._rx_ready.set()
        await self._close_quietly()

    async def _close_quietly(self) -> None:
        try:
            await self._close()
        except (OSError, LinkError, RuntimeError):
            pass  # the transport is already gone; closing it is best effort

    async def __aenter__(self) -> Link:
        await self.connect()
        return self

    async def __aexit__(self, *exc_info) -> None:
        await self.close()

    def _describe(self) -> str:
        """Where the link goes (port, address, command), for messages."""
        return type(self).__name__

    # -- writing ------------------------------------------------------------------------------------

    async def write(self, data: bytes, timeout_s: float | None = None) -> None:
        """Send `data`; returns once the transport has taken all of it (back-pressure applies)."""
        self._check_usable(f"sending {len(data)} bytes")
        timeout_s = self.write_timeout_s if timeout_s is None else timeout_s
        try:
            async with asyncio.timeout(timeout_s):
                await self._send(bytes(data))
        except TimeoutError:
            raise LinkTimeout(f"room to send {len(data)} bytes", self.hub, timeout_s) from None
        self.bytes_sent += len(data)

    # -- reading ------------------------------------------------------------------------------------

    def available(self) -> int:
        """How many received bytes wait to be read."""
        return len(self._rx)

    def take(self, max_bytes: int | None = None) -> bytes:
        """Take buffered bytes without waiting (b"" if none)."""
        n = len(self._rx) if max_bytes is None else min(max_bytes, len(self._rx))
        data = bytes(self._rx[:n])
        del self._rx[:n]
        return data

    def unread(self, data: bytes) -> None:
        """Put bytes a reader took but does not own back in front of the buffer (the next read
        gets them first): a parser that read past the end of its part hands the rest on."""
        if data:
            self._rx[:0] = data
            self._rx_ready.set()

    async def _wait_for_data(self, what: str, deadline: float, timeout_s: float) -> None:
        while not self._rx:
            self._check_usable(f"waiting for {what}")
            self._rx_ready.clear()
            remaining = deadline - asyncio.get_running_loop().time()
            if remaining <= 0:
                raise LinkTimeout(what, self.hub, timeout_s)
            try:
                async with asyncio.timeout(remaining):
                    await self._rx_ready.wait()
            except TimeoutError:
                raise LinkTimeout(what, self.hub, timeout_s) from None

    async def wait_readable(self, what: str, timeout_s: float) -> None:
        """Wait until at least one received byte is buffered, without taking it."""
        deadline = asyncio.get_running_loop().time() + timeout_s
        await self._wait_for_data(what, deadline, timeout_s)

    async def read_some(self, what: str, timeout_s: float) -> bytes:
        """Whatever has arrived (at least one byte), waiting up to `timeout_s` for it."""
        deadline = asyncio.get_running_loop().time() + timeout_s
        await self._wait_for_data(what, deadline, timeout_s)
        return self.take()

    async def read_exactly(self, n: int, what: str, timeout_s: float) -> bytes:
        deadline = asyncio.get_running_loop().time() + timeout_s
        while len(self._rx) < n:
            self._check_usable(f"waiting for {what}")
            self._rx_ready.clear()
            remaining = deadline - asyncio.get_running_loop().time()
            try:
                async with asyncio.timeout(max(remaining, 0)):
                    await self._rx_ready.wait()
            except TimeoutError:
                raise LinkTimeout(what, self.hub, timeout_s) from None
        return self.take(n)

    async def read_until(
        self,
        marker: bytes,
        what: str,
        timeout_s: float,
        on_data: Callable[[bytes], None] | None = None,
    ) -> bytes:
        """Bytes up to (not including) `marker`, which is consumed too.

        With `on_data`, bytes are handed to it as they arrive (held back only while they could be
        the start of the marker) and the return value is just what was left after the last call.
        """
        loop = asyncio.get_running_loop()
        deadline = loop.time() + timeout_s
        kept = bytearray()
        while True:
            at = self._rx.find(marker)
            if at >= 0:
                found = bytes(self._rx[:at])
                del self._rx[: at + len(marker)]
                if on_data is not None:
                    if found:
                        on_data(found)
                    return b""
                return bytes(kept) + found
            if self._rx:
                safe = len(self._rx) - _partial_marker_tail(self._rx, marker)
                if safe:
                    chunk = bytes(self._rx[:safe])
                    del self._rx[:safe]
                    if on_data is not None:
                        on_data(chunk)
                    else:
                        kept += chunk
            self._check_usable(f"waiting for {what}")
            self._rx_ready.clear()
            remaining = deadline - loop.time()
            try:
                async with asyncio.timeout(max(remaining, 0)):
                    await self._rx_ready.wait()
            except TimeoutError:
                raise LinkTimeout(what, self.hub, timeout_s) from None

    async def chunks(self, timeout_s: float, what: str = "output") -> AsyncIterator[bytes]:
        """The received byte stream as an async iterator of chunks, until the link closes.

        Raises LinkDropped when the link drops (after everything received was yielded) and
        LinkTimeout when nothing arrives for `timeout_s`.
        """
        while True:
            try:
                yield await self.read_some(what, timeout_s)
            except LinkClosed:
                return


def _partial_marker_tail(buffer: bytearray, marker: bytes) -> int:
    """Length of the longest tail of `buffer` that is a proper prefix of `marker`."""
    for n in range(min(len(marker) - 1, len(buffer)), 0, -1):
        if buffer.endswith(marker[:n]):
            return n
    return 0
