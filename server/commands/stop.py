"""`openbricks stop`: interrupt whatever program the hub runs, and confirm it is idle."""

from __future__ import annotations

import asyncio

from openbricks_server.errors import EXIT_OK, CliError
from openbricks_server.hub_session import with_hub


async def _talk(session):
    # Entering the raw REPL (done by the session) sends Ctrl-C: the program is already stopped here;
    # `info` was read after it, so `running` is the hub's own confirmation.
    if session.info.running:
        raise CliError(
            f"{session.name} still reports a running program after Ctrl-C; press its program button"
        )
    return session.name


def main(args) -> int:
    name = asyncio.run(with_hub(args.name, args.scan_timeout, _talk))
    print(f"{name}: no program running")
    return EXIT_OK
