"""A real console daemon for tests: the app from `create_app` under uvicorn on 127.0.0.1 (a free port),
served from a thread of the test process so tests can also drive the `HubEvents` seam directly, the way
hub actors do, on the daemon's own event loop.
"""

from __future__ import annotations

import asyncio
import socket
import threading
import time
from contextlib import asynccontextmanager
from dataclasses import replace
from pathlib import Path

import httpx
import pytest
import uvicorn
from websockets.sync.client import connect

from openbricks_server.daemon.app import SERVICES, DaemonContext, create_app
from openbricks_server.daemon.config import DaemonConfig
from openbricks_server.daemon.serve import bind, uvicorn_config
from tests.server.flash.conftest import fake_esptool  # noqa: F401 - flash jobs run the fake esptool

START_TIMEOUT_S = 20


class Daemon:
    """A running daemon: its URL, its local operator token, and its context (store, bus, hub events)."""

    def __init__(self, config: DaemonConfig, services=None):
        sock = bind(config)
        self.config = replace(config, port=sock.getsockname()[1])
        self.loop: asyncio.AbstractEventLoop | None = None

        @asynccontextmanager
        async def capture_loop(ctx: DaemonContext):
            self.loop = asyncio.get_running_loop()
            yield

        chosen = list(SERVICES if services is None else services)
        self.app = create_app(self.config, services=[*chosen, capture_loop])
        self.ctx: DaemonContext = self.app.state.ctx
        self.server = uvicorn.Server(uvicorn_config(self.app))
        self.thread = threading.Thread(target=self.server.run, kwargs={"sockets": [sock]}, daemon=True)
        self.thread.start()
        deadline = time.monotonic() + START_TIMEOUT_S
        while not self.server.started:
            if not self.thread.is_alive() or time.monotonic() > deadline:
                raise RuntimeError("the daemon did not start")
            time.sleep(0.01)
        self.url = self.config.url()
        self.token = self.ctx.auth.local_token
        self.ws_url = self.url.replace("http://", "ws://") + "/api/events"
        self.origin = self.url

    def client(self, token: str | None = None, **kwargs) -> httpx.Client:
        headers = {"Authorization": f"Bearer {token or self.token}"}
        return httpx.Client(base_url=self.url, headers=headers, timeout=30, **kwargs)

    def websocket(self, query: str = "", token: str | None = None, origin: str | None = None, rcvbuf=None):
        """A WebSocket client; `rcvbuf` shrinks its socket's receive buffer (a client on a slow link)."""
        sock = socket.socket(socket.AF_INET, socket.SOCK_STREAM)
        if rcvbuf:
            sock.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, rcvbuf)
        sock.settimeout(30)
        sock.connect(("127.0.0.1", self.config.port))
        return connect(
            sock=sock,
            uri=self.ws_url + (f"?{query}" if query else ""),
            origin=origin or self.origin,
            additional_headers={"Authorization": f"Bearer {token or self.token}"},
            open_timeout=30,
            close_timeout=2,
            max_size=None,
        )

    def call(self, fn, *args, timeout: float = 30):
        """Run `fn(*args)` on the daemon's event loop (where hub actors call HubEvents) and return it."""

        async def run():
            return fn(*args)

        return asyncio.run_coroutine_threadsafe(run(), self.loop).result(timeout)

    def stop(self) -> None:
        self.server.should_exit = True
        self.thread.join(15)


def start_daemon(data_dir: Path, **config) -> Daemon:
    return Daemon(DaemonConfig(host="127.0.0.1", port=0, virtual=0, ble=False, data_dir=data_dir, **config))


@pytest.fixture
def daemon(tmp_path):
    running = start_daemon(tmp_path / "data")
    yield running
    running.stop()


@pytest.fixture
def operator(daemon):
    with daemon.client() as client:
        yield client


@pytest.fixture
def viewer_token(daemon):
    return daemon.ctx.store.tokens.mint("viewer", "mentor")


@pytest.fixture
def viewer(daemon, viewer_token):
    with daemon.client(viewer_token) as client:
        yield client
