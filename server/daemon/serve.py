"""Serving the app: bind the socket ourselves (a busy port is one clear line, not a uvicorn traceback),
then run one uvicorn worker on it until Ctrl-C or SIGTERM, which shut down cleanly: services (hubs,
virtual hub processes, the output writer) are closed, the runtime file removed."""

from __future__ import annotations

import errno
import os
import socket
from collections.abc import AsyncIterator, Callable
from contextlib import asynccontextmanager
from dataclasses import replace

from openbricks_server.daemon import runtime_file
from openbricks_server.daemon.app import SERVICES, DaemonContext, create_app
from openbricks_server.daemon.config import DaemonConfig

WS_MAX_MESSAGE_BYTES = 256 * 1024


class BindError(Exception):
    pass


def bind(config: DaemonConfig) -> socket.socket:
    family = socket.AF_INET6 if ":" in config.host else socket.AF_INET
    sock = socket.socket(family, socket.SOCK_STREAM)
    sock.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
    try:
        sock.bind((config.host.strip("[]"), config.port))
    except OSError as exc:
        sock.close()
        if exc.errno == errno.EADDRINUSE:
            raise BindError(
                f"port {config.port} on {config.host} is in use: is a console already running? Stop it, or "
                "start this one with --port PORT"
            ) from None
        raise BindError(f"cannot listen on {config.host}:{config.port} ({exc.strerror})") from None
    sock.listen(128)
    sock.set_inheritable(True)
    return sock


def announce(print_line: Callable[[str], None]):
    """A service (the last one) that publishes the runtime file and prints the sign-in URL once
    everything else has started, and removes the file first thing at shutdown."""

    @asynccontextmanager
    async def service(ctx: DaemonContext) -> AsyncIterator[None]:
        info = runtime_file.RuntimeInfo(
            url=ctx.config.url(),
            token=ctx.auth.local_token,
            pid=os.getpid(),
            data_dir=str(ctx.config.resolved_data_dir),
        )
        runtime_file.write(info)
        print_line(f"openbricks console: open {info.sign_in_url}")
        print_line(f"  data in {ctx.config.resolved_data_dir}; Ctrl-C stops the console and its virtual hubs")
        try:
            yield
        finally:
            runtime_file.remove(os.getpid())

    return service


def run(config: DaemonConfig, print_line: Callable[[str], None] = print) -> bool:
    """Serve until stopped; False if start-up failed (the reason was printed)."""
    import uvicorn

    sock = bind(config)
    config = replace(config, port=sock.getsockname()[1])
    app = create_app(config, services=[*SERVICES, announce(print_line)])
    server = uvicorn.Server(uvicorn_config(app))
    server.run(sockets=[sock])
    return server.started


def uvicorn_config(app):
    """One worker, asyncio, quiet. No per-message compression on the event stream: deflating every
    message once per client costs more CPU than the fan-out itself, and the console runs on a laptop
    serving its own network."""
    import uvicorn

    return uvicorn.Config(
        app,
        log_level="warning",
        lifespan="on",
        ws_max_size=WS_MAX_MESSAGE_BYTES,
        ws_per_message_deflate=False,
        timeout_graceful_shutdown=5,
        access_log=False,
    )
