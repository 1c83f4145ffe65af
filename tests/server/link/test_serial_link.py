"""The serial link through pyserial on a pseudo-terminal pair, with the emulated hub on the other end."""

import asyncio
import os
import tty

import pytest

from openbricks_server.link import HubNotFound, LinkDropped
from openbricks_server.link.raw_repl import RawRepl
from openbricks_server.link.serial_link import SerialLink
from tests.server.link.scripted_hub import ScriptedHub


def run(coro, timeout_s=30):
    async def bounded():
        async with asyncio.timeout(timeout_s):
            return await coro

    return asyncio.run(bounded())


class PtyHub:
    """The emulated hub serving the controller side of a pty; the link opens the other side."""

    def __init__(self, hub: ScriptedHub):
        self.hub = hub
        self.controller, peer = os.openpty()
        tty.setraw(peer)  # bytes cross unchanged, as on a USB CDC port
        self.path = os.ttyname(peer)
        self._peer = peer
        loop = asyncio.get_running_loop()
        hub.attach(self._write, loop)
        os.set_blocking(self.controller, False)
        loop.add_reader(self.controller, self._readable)

    def _write(self, data: bytes) -> None:
        view = memoryview(data)
        while view:
            try:
                view = view[os.write(self.controller, view) :]
            except BlockingIOError:
                continue

    def _readable(self) -> None:
        try:
            data = os.read(self.controller, 4096)
        except OSError:
            return
        if data:
            self.hub.feed(data)

    def unplug(self) -> None:
        asyncio.get_running_loop().remove_reader(self.controller)
        os.close(self.controller)
        os.close(self._peer)


def test_a_session_over_a_serial_port():
    async def scenario():
        pty_hub = PtyHub(ScriptedHub("RobotA", stdin_buffer_max=256))
        link = SerialLink(pty_hub.path, hub="RobotA")
        await link.connect()
        repl = RawRepl(link, timeout_s=5)
        await repl.enter()
        assert (await repl.exec("print('over usb')")).stdout == b"over usb\r\n"
        data = os.urandom(6000)
        await repl.put("/program.mpy", data, compress=False)
        assert pty_hub.hub.files["/program.mpy"] == data
        assert pty_hub.hub.overflow_bytes == 0
        await link.close()
        pty_hub.unplug()

    run(scenario())


def test_an_unplugged_port_is_a_drop_that_keeps_what_arrived():
    async def scenario():
        pty_hub = PtyHub(ScriptedHub("RobotA"))
        link = SerialLink(pty_hub.path, hub="RobotA")
        await link.connect()
        repl = RawRepl(link, timeout_s=5)
        await repl.enter()
        dropped = asyncio.Event()
        link.on_drop(lambda _drop: dropped.set())
        pty_hub._write(b"partial output")
        await asyncio.sleep(0.2)
        pty_hub.unplug()
        async with asyncio.timeout(2):
            await dropped.wait()
        assert link.take() == b"partial output"
        with pytest.raises(LinkDropped, match="link to RobotA dropped"):
            await repl.exec("print(1)")
        await link.close()

    run(scenario())


def test_a_missing_port_names_it():
    with pytest.raises(HubNotFound, match="cannot open /dev/ttyNOPE for RobotA"):
        run(SerialLink("/dev/ttyNOPE", hub="RobotA").connect())
