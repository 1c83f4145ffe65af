"""The Link contract every transport shares: buffering, drops that keep data, timeouts that say what."""

import asyncio

import pytest

from openbricks_server.link import LinkClosed, LinkDropped, LinkError, LinkTimeout
from openbricks_server.link.base import Link
from tests.server.link.loopback import LoopbackLink
from tests.server.link.scripted_hub import ScriptedHub


def run(coro, timeout_s=20):
    async def bounded():
        async with asyncio.timeout(timeout_s):
            return await coro

    return asyncio.run(bounded())


class FedLink(Link):
    """A link whose received bytes the test pushes in by hand."""

    can_reconnect = True

    async def _open(self):
        pass

    async def _send(self, data):
        pass

    async def _close(self):
        pass


def test_read_until_returns_what_precedes_the_marker_and_consumes_it():
    async def scenario():
        link = FedLink("RobotA")
        await link.connect()
        link._received(b"OK hello\x04rest")
        assert await link.read_until(b"\x04", "output", 1) == b"OK hello"
        assert link.take() == b"rest"

    run(scenario())


def test_streamed_reads_hand_over_bytes_as_they_come_but_never_half_a_marker():
    async def scenario():
        link = FedLink("RobotA")
        await link.connect()
        got = []
        reader = asyncio.create_task(link.read_until(b"\r\n>", "prompt", 2, on_data=got.append))
        link._received(b"line one\r")
        await asyncio.sleep(0.01)
        assert got == [b"line one"]  # the "\r" may start the marker: held back
        link._received(b"\nmore\r\n>tail")
        assert await reader == b""
        assert b"".join(got) == b"line one\r\nmore"
        assert link.take() == b"tail"

    run(scenario())


def test_a_silent_hub_times_out_with_what_was_awaited():
    async def scenario():
        link = FedLink("RobotA")
        await link.connect()
        with pytest.raises(LinkTimeout, match=r"waiting for the raw REPL banner from RobotA after 0\.05 s"):
            await link.read_until(b">", "the raw REPL banner", 0.05)

    run(scenario())


def test_a_connect_that_never_completes_times_out():
    async def scenario():
        link = LoopbackLink(ScriptedHub("RobotB"))
        link.refuse_connect = True
        with pytest.raises(
            LinkTimeout, match=r"waiting for a connection \(loopback\) from RobotB after 0\.05 s"
        ):
            await link.connect(timeout_s=0.05)

    run(scenario())


def test_data_received_before_a_drop_is_still_read_then_the_drop_is_raised():
    async def scenario():
        link = FedLink("RobotA")
        await link.connect()
        drops = []
        link.on_drop(drops.append)
        link._received(b"last words\x04")
        link._dropped("supervision timeout")
        assert len(drops) == 1 and link.disconnected.is_set()
        assert await link.read_until(b"\x04", "output", 1) == b"last words"
        with pytest.raises(
            LinkDropped, match="link to RobotA dropped while waiting for output: supervision timeout"
        ):
            await link.read_some("output", 1)

    run(scenario())


def test_a_blocked_reader_wakes_at_the_drop_not_at_its_timeout():
    async def scenario():
        link = FedLink("RobotA")
        await link.connect()
        loop = asyncio.get_running_loop()
        reader = asyncio.create_task(link.read_until(b"\x04", "program output", 30))
        await asyncio.sleep(0.01)
        started = loop.time()
        link._dropped("hub out of range")
        with pytest.raises(LinkDropped):
            await reader
        assert loop.time() - started < 0.5

    run(scenario())


def test_the_buffer_survives_a_reconnect():
    async def scenario():
        link = FedLink("RobotA")
        await link.connect()
        link._received(b"before ")
        link._dropped("gone")
        await link.reconnect()
        link._received(b"after\x04")
        assert await link.read_until(b"\x04", "output", 1) == b"before after"

    run(scenario())


def test_a_closed_link_refuses_writes_and_reads():
    async def scenario():
        link = FedLink("RobotA")
        await link.connect()
        await link.close()
        with pytest.raises(LinkClosed, match="link to RobotA is closed"):
            await link.write(b"x")
        with pytest.raises(LinkClosed):
            await link.read_some("output", 1)

    run(scenario())


def test_a_link_that_cannot_reconnect_says_so():
    class OneShot(FedLink):
        can_reconnect = False

    async def scenario():
        link = OneShot("RobotA")
        await link.connect()
        link._dropped("process exited")
        with pytest.raises(LinkError, match="cannot reconnect"):
            await link.reconnect()

    run(scenario())


def test_the_chunk_stream_ends_when_the_link_is_closed():
    async def scenario():
        link = FedLink("RobotA")
        await link.connect()
        link._received(b"abc")
        stream = link.chunks(1)
        assert await anext(stream) == b"abc"
        await link.close()
        with pytest.raises(StopAsyncIteration):
            await anext(stream)

    run(scenario())
