"""Program names and texts the daemon accepts: checked before anything is stored or sent to a hub.

The syntax check compiles to an AST with CPython's `compile()` (never executed): MicroPython's grammar is
Python 3's, so a syntax error is reported with file, line and column in milliseconds, before a hub is
involved. Hubs still compile with mpy-cross when a program is sent.
"""

from __future__ import annotations

import ast
import re

from openbricks_server.compile import MAX_PROGRAM_BYTES
from openbricks_server.daemon.errors import ApiError

NAME_PATTERN = r"^[A-Za-z0-9_][A-Za-z0-9_.-]{0,63}$"
_NAME = re.compile(NAME_PATTERN)
# Control characters a text file does not contain (tab, newline, form feed and carriage return are text).
_BINARY = re.compile(r"[\x00-\x08\x0b\x0e-\x1f\x7f]")


def check_name(name: str) -> str:
    """A program name safe as a file name on the hub and in exports: letters, digits, `_ . -`, no path."""
    if not _NAME.fullmatch(name) or ".." in name:
        raise ApiError.invalid(
            "bad_program_name",
            f"{name[:80]!r} is not a program name",
            "use 1-64 letters, digits, '_', '.' or '-' (no '/', no '..', not starting with '.' or '-'), "
            "e.g. square.py",
        )
    return name


def check_source(name: str, source: str) -> None:
    """Refuse what cannot run on a hub: too big, binary, not UTF-8, or not valid Python syntax."""
    try:
        size = len(source.encode("utf-8"))
    except UnicodeEncodeError as exc:
        line = source[: exc.start].count("\n") + 1
        raise ApiError.invalid(
            "not_utf8",
            f"{name}, line {line}: a character that cannot be UTF-8 encoded (a lone surrogate)",
            "save the file as UTF-8 text",
            {"file": name, "line": line},
        ) from None
    if size > MAX_PROGRAM_BYTES:
        raise ApiError(
            413,
            "program_too_large",
            f"{name} is {size} bytes; a hub takes programs up to {MAX_PROGRAM_BYTES} bytes",
            "split it into modules, or move data out of the source",
            {"file": name, "size": size, "limit": MAX_PROGRAM_BYTES},
        )
    binary = _BINARY.search(source)
    if binary:
        line = source[: binary.start()].count("\n") + 1
        raise ApiError.invalid(
            "binary_program",
            f"{name}, line {line}: control character 0x{ord(binary.group()):02x}; this is not a text file",
            "send the program's .py source, not a compiled or binary file",
            {"file": name, "line": line},
        )
    try:
        compile(source, name, "exec", flags=ast.PyCF_ONLY_AST, dont_inherit=True)
    except SyntaxError as exc:
        line = exc.lineno or 0
        text = (exc.text or "").rstrip("\n")
        raise ApiError.invalid(
            "syntax_error",
            f"{name}, line {line}: {exc.msg}" + (f": {text.strip()}" if text.strip() else ""),
            "fix the line shown; nothing was stored or sent to a hub",
            {"file": name, "line": line, "column": exc.offset, "text": text},
        ) from None
    except (RecursionError, MemoryError):
        raise ApiError.invalid(
            "program_too_complex",
            f"{name}: nested too deeply to compile",
            "flatten the deepest nesting of brackets or blocks",
            {"file": name},
        ) from None
