"""A `Link` wired straight to an emulated hub in the same loop: the raw-REPL client's unit-test bench.

Bytes cross in both directions through the loop (never synchronously inside a write), so ordering
and interleaving are as on a real transport, minus its timing. `drop()` cuts the link as a radio
would; output the hub makes while the link is down is held and delivered after `reconnect()`.
"""

from __future__ import annotations

import asyncio

from openbricks_server.link.base import Link
from tests.server.link.scripted_hub import ScriptedHub


class LoopbackLink(Link):
    can_reconnect = True

    def __init__(self, hub: ScriptedHub, **kwargs):
        super().__init__(hub.name, **kwargs)
        self.scripted = hub
        self.writes: list[bytes] = []
        self.held = bytearray()
        self._up = False
        self.refuse_connect = False

    def _describe(self) -> str:
        return "loopback"

    async def _open(self) -> None:
        if self.refuse_connect:
            await asyncio.Event().wait()  # never answers: the connect timeout must fire
        loop = asyncio.get_running_loop()
        self.scripted.attach(self._from_hub, loop)
        self._up = True
        if self.held:
            held = bytes(self.held)
            self.held.clear()
            loop.call_soon(self._received, held)

    def _from_hub(self, data: bytes) -> None:
        if self._up:
            self._received(data)
        else:
            self.held += data

    async def _send(self, data: bytes) -> None:
        self.writes.append(data)
        asyncio.get_running_loop().call_soon(self.scripted.feed, data)
        await asyncio.sleep(0)

    async def _close(self) -> None:
        self._up = False

    def drop(self, reason: str = "supervision timeout") -> None:
        self._up = False
        self._dropped(reason)
