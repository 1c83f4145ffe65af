"""Putting a checked program on a hub: bytecode where the hub can load it, source where it cannot.

A hub loads compiled programs when its runtime reports a .mpy version (`info`: accepts_mpy,
mpy_version) matching what our mpy-cross emits. Anything else (older firmware, a virtual hub, which
runs CPython) gets the source at `/program.py` instead, announced on stderr, never silently. The
hub's own size limit is checked before anything is sent.
"""

from __future__ import annotations

import sys

from openbricks.log import LOG_DIR
from openbricks_server.compile import Program, ProgramError, check_size, compile_program
from openbricks_server.errors import CliError, UsageError
from openbricks_server.link import HubCallError

SOURCE_PROGRAM_PATH = "/program.py"
# Beside a staged source, its size and the program's own name: the hub's launcher reads it for a run
# started by the program button, so that traceback names `square.py` too, not /program.py.
SOURCE_NAME_PATH = "/program.name"
MPY_MAJOR = 6  # the .mpy format our mpy-cross writes (byte 1 of the file)


class StorageError(CliError):
    """The hub could not store the file where it was asked to (no such folder, a file in the way, full)."""


def check_hub_path(path: str) -> None:
    """A hub file path to store a file at, absolutely, and not where the runtime keeps its own files."""
    parts = path.split("/")[1:]
    if not path.startswith("/") or path.endswith("/"):
        problem = "give an absolute hub file path"
    elif any(part in ("", ".", "..") for part in parts):
        problem = "empty, '.' and '..' parts are not allowed; write the path out"
    elif any(not ch.isprintable() for ch in path):
        problem = "it contains control characters"
    elif path == LOG_DIR or path.startswith(LOG_DIR + "/") or path.startswith(LOG_DIR + "."):
        problem = "the hub keeps its run logs there; store the file elsewhere"
    else:
        return
    raise UsageError(f"--path {path!r}: {problem}, such as /lib/tools.py")


def takes_bytecode(info) -> bool:
    return bool(info.accepts_mpy) and info.mpy_version == MPY_MAJOR


def _to_stderr(text: str) -> None:
    print(text, file=sys.stderr)


async def stage(session, program: Program, path: str | None = None, notice=_to_stderr) -> str:
    """Stage `program` on the hub; returns the hub path it landed at. `notice(text)` hears why the
    source goes instead of bytecode (the terminal's stderr; the console's log)."""
    info = session.info
    if path is not None:  # upload --path: the file as it is, where the user says
        check_hub_path(path)
        data, target = program.source_bytes, path
    elif takes_bytecode(info) and program.mpy is not None:
        data, target = program.mpy, info.program_path
    else:
        reason = (
            "it is a virtual hub" if session.virtual else f"its runtime ({info.runtime}) loads no .mpy v6"
        )
        notice(f"{session.name} cannot load compiled programs ({reason}): sending the source")
        data, target = program.source_bytes, SOURCE_PROGRAM_PATH
    if info.max_program_bytes:
        try:
            check_size(len(data), f"{program.filename} is", info.max_program_bytes)
        except ProgramError as exc:
            raise ProgramError(f"{exc} (the limit of {session.name})") from None
    try:
        await session.repl.put(target, data)
        if path is None and target == SOURCE_PROGRAM_PATH:
            await session.repl.put(SOURCE_NAME_PATH, f"{len(data)}\n{program.filename}".encode())
    except HubCallError as exc:
        raise StorageError(
            f"{session.name} could not store {target}: {_storage_problem(target, exc)}"
        ) from None
    return target


def _storage_problem(path: str, exc: HubCallError) -> str:
    """The hub's file error (MicroPython names only the errno) as what to change."""
    folder = path.rsplit("/", 1)[0] or "/"
    if "ENOENT" in exc.error:
        return f"there is no folder {folder} on the hub; store it in an existing folder such as /"
    if "ENOTDIR" in exc.error:
        return f"part of {folder} is a file on the hub, not a folder"
    if "EISDIR" in exc.error:
        return f"{path} is a folder on the hub; name a file inside it, e.g. {path}/tools.py"
    if "ENOSPC" in exc.error:
        return "the hub's flash is full; remove files you no longer need, or store a smaller file"
    return exc.error


def prepare(program: Program) -> Program:
    """Compile before any hub is looked for: syntax errors surface at once."""
    return compile_program(program)
