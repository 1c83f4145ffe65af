"""`openbricks log`: the run logs kept on the hub, with stamps in local time."""

from __future__ import annotations

import asyncio
import sys

from openbricks_server.errors import EXIT_OK, CliError
from openbricks_server.hub_session import with_hub
from openbricks_server.logview import LogRenderer, missing_run, print_runs


async def _talk(session, args):
    listing = await session.call("runs")
    runs = listing["runs"]
    if args.list:
        print_runs(session.name, runs, args.json)
        return
    indices = [entry["index"] for entry in runs]
    if not indices:
        raise CliError(f"{session.name} has no run logs yet: runs are logged when a program runs")
    index = indices[-1] if args.run is None else args.run
    if index not in indices:
        raise CliError(missing_run(session.name, index, indices, listing.get("slots", len(indices))))
    out = sys.stdout
    renderer = LogRenderer(out.write)
    offset = 0
    while offset is not None:
        text, offset = await session.repl.read_run_page(index, offset)
        renderer.feed(text)
        out.flush()
    renderer.finish()


def main(args) -> int:
    from openbricks_server import console_client

    console = console_client.running()
    if console is not None:  # the console owns the hub links: through it
        return console_client.log(console, args)
    asyncio.run(with_hub(args.name, args.scan_timeout, lambda session: _talk(session, args)))
    return EXIT_OK
