"""`openbricks upload`: stage a program as the hub's button program (or a file, verbatim, with --path)."""

from __future__ import annotations

import asyncio
import sys
from pathlib import Path

from openbricks_server.compile import Program, check_size, read_file, read_program
from openbricks_server.errors import EXIT_OK
from openbricks_server.hub_session import with_hub
from openbricks_server.staging import check_hub_path, prepare, stage


def _verbatim(path: str) -> Program:
    """--path: the file's bytes as they are; it may be data, so only existence and size are checked."""
    source = Path(path)
    data = read_file(source)
    check_size(len(data), f"{source} is")
    return Program(source.name, data.decode("utf-8", "surrogateescape"))


def main(args) -> int:
    if args.path is not None:
        check_hub_path(args.path)
        program = _verbatim(args.script)
    else:
        program = prepare(read_program(args.script))

    from openbricks_server import console_client

    console = console_client.running()
    if console is not None:  # the console owns the hub links: through it
        return console_client.upload(console, args, program)

    async def talk(session):
        target = await stage(session, program, args.path)
        return target

    target = asyncio.run(with_hub(args.name, args.scan_timeout, talk))
    if args.path is None:
        print(f"staged {program.filename} at {target} on {args.name}: press the program button to start it")
    else:
        print(f"stored {program.filename} at {target} on {args.name}, as it is", file=sys.stdout)
    return EXIT_OK
