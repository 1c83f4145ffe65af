"""`openbricks log`: the run logs kept on the hub, with stamps in local time."""

from __future__ import annotations

import asyncio
import sys

from openbricks_server.errors import EXIT_OK, CliError
from openbricks_server.hub_session import with_hub
from openbricks_server.logview import LogRenderer


async def _talk(session, args):
    runs = (await session.call("runs"))["runs"]
    if args.list:
        if not runs:
            print(f"{session.name} has no run logs yet")
        for entry in runs:
            print(f"run {entry['index']:>4}  {entry['bytes']:>7} bytes")
        return
    indices = [entry["index"] for entry in runs]
    if not indices:
        raise CliError(f"{session.name} has no run logs yet: runs are logged when a program runs")
    index = indices[-1] if args.run is None else args.run
    if index not in indices:
        raise CliError(
            f"{session.name} has no log of run {index} (kept: {', '.join(str(i) for i in indices)}); older "
            "runs were overwritten"
        )
    out = sys.stdout
    renderer = LogRenderer(out.write)
    offset = 0
    while offset is not None:
        part = await session.call("read_run", index=index, offset=offset)
        renderer.feed(part["text"])
        out.flush()
        offset = part["next_offset"]
    renderer.finish()


def main(args) -> int:
    asyncio.run(with_hub(args.name, args.scan_timeout, lambda session: _talk(session, args)))
    return EXIT_OK
