"""`openbricks stop`: interrupt whatever program the hub runs, confirm it is idle, and say which
program it stopped (if any), from the hub's own record of how its latest run ended."""

from __future__ import annotations

import asyncio

from openbricks_server.errors import EXIT_OK, CliError
from openbricks_server.hub_session import with_hub


def stopped_by_us(last_run: dict | None) -> bool:
    """True when the hub's latest run was stopped by a console Ctrl-C after its last host-call
    reply, which makes it the Ctrl-C that opened this session."""
    return bool(
        last_run
        and last_run.get("outcome") == "stopped"
        and last_run.get("stopped_by") == "console"
        and last_run.get("since_last_call")
    )


async def _talk(session):
    # Entering the raw REPL (done by the session) sends Ctrl-C: the program is already stopped here;
    # `info` was read after it, so `running` is the hub's own confirmation.
    if session.info.running:
        raise CliError(
            f"{session.name} still reports a running program after Ctrl-C; press its program button"
        )
    last = session.info.last_run
    if stopped_by_us(last):
        return f"{session.name}: stopped the program (run {last['index']}, started by {last['trigger']})"
    return f"{session.name}: no program was running"


def main(args) -> int:
    from openbricks_server import console_client

    console = console_client.running()
    if console is not None:  # the console owns the hub links: through it
        return console_client.stop(console, args)
    print(asyncio.run(with_hub(args.name, args.scan_timeout, _talk)))
    return EXIT_OK
