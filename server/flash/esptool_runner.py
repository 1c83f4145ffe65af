"""esptool as a separate process, with its output read for the chip name and the write progress.

esptool is GPL-licensed and configures a process-wide logger, so it never runs inside our process: the
CLI and the console daemon (flashing twenty hubs at once, one process per port) start `python -m esptool`
per operation as an asyncio subprocess and parse what it prints; a cancelled operation kills its esptool.
Both output styles are understood: esptool 5's one-line-per-update progress bar
("Writing at 0x00010000 [====   ]  35.1% 12345/65536 bytes ...") and esptool 4's
"Writing at 0x00010000... (35 %)"; lines may end in \\r (redrawn in place) or \\n.

OPENBRICKS_ESPTOOL names another esptool executable (one program path); the tests point it at a fake
that records its arguments.
"""

from __future__ import annotations

import asyncio
import os
import re
import shlex
import sys
from collections.abc import Callable
from dataclasses import dataclass, field

from openbricks_server.errors import CliError

ESPTOOL_ENV = "OPENBRICKS_ESPTOOL"
_CHIP_LINE = re.compile(
    r"(?:Chip type:|Chip is|Detecting chip type\.\.\.)\s*(ESP32(?:-[A-Z0-9]+)?)", re.IGNORECASE
)
_PROGRESS = re.compile(r"Writing at (0x[0-9a-fA-F]+)\D.*?(\d{1,3}(?:\.\d+)?)\s*%")
_LINE_END = re.compile(rb"[\r\n]")


class EsptoolError(CliError):
    """esptool failed; the message carries its own explanation."""


@dataclass
class EsptoolResult:
    lines: list[str] = field(default_factory=list)


def esptool_command() -> list[str]:
    override = os.environ.get(ESPTOOL_ENV)
    if override:
        return [override]
    return [sys.executable, "-m", "esptool"]


def chip_name(esptool_chip: str) -> str:
    """'ESP32-S3' -> 'esp32s3' (esptool's --chip spelling)."""
    return esptool_chip.lower().replace("-", "")


def parse_chip(lines: list[str]) -> str | None:
    for line in lines:
        found = _CHIP_LINE.search(line)
        if found:
            return chip_name(found.group(1))
    return None


def parse_progress(line: str) -> float | None:
    """Percent written, from one line of esptool output, or None if the line is not progress."""
    found = _PROGRESS.search(line)
    return float(found.group(2)) if found else None


class Esptool:
    """Runs esptool operations on one port; `echo` receives command lines (for --verbose)."""

    def __init__(self, port: str, echo: Callable[[str], None] | None = None):
        self.port = port
        self.echo = echo

    async def _run(
        self, args: list[str], on_line: Callable[[str], None] | None = None, what: str = ""
    ) -> EsptoolResult:
        argv = esptool_command() + args
        if self.echo:
            self.echo("$ " + shlex.join(argv))
        try:
            proc = await asyncio.create_subprocess_exec(
                *argv,
                stdout=asyncio.subprocess.PIPE,
                stderr=asyncio.subprocess.STDOUT,
                stdin=asyncio.subprocess.DEVNULL,
                start_new_session=True,  # a Ctrl-C at the terminal is ours to handle, not esptool's
            )
        except OSError as exc:
            raise EsptoolError(
                f"could not start esptool ({argv[0]}: {exc.strerror}); reinstall openbricks"
            ) from None
        result = EsptoolResult()
        pending = b""
        assert proc.stdout is not None
        try:
            while True:
                chunk = await proc.stdout.read(4096)
                if not chunk:
                    break
                pending += chunk
                parts = _LINE_END.split(pending)
                pending = parts.pop()
                for raw in parts:
                    self._line(raw, result, on_line)
            if pending:
                self._line(pending, result, on_line)
            await proc.wait()
        finally:
            if proc.returncode is None:  # cancelled (or the reader failed): esptool must not live on
                proc.kill()
                await proc.wait()
        if proc.returncode != 0:
            raise EsptoolError(_failure(what, self.port, result.lines, proc.returncode))
        return result

    @staticmethod
    def _line(raw: bytes, result: EsptoolResult, on_line) -> None:
        line = raw.decode("utf-8", "replace").rstrip()
        if not line:
            return
        result.lines.append(line)
        if on_line:
            on_line(line)

    async def probe_chip(self) -> str:
        """The connected chip's esptool name (e.g. 'esp32s3')."""
        result = await self._run(["--chip", "auto", "--port", self.port, "chip-id"], what="probing the chip")
        chip = parse_chip(result.lines)
        if chip is None:
            raise EsptoolError(
                f"esptool answered on {self.port} but did not name the chip: " + " | ".join(result.lines[-3:])
            )
        return chip

    async def erase(self, chip: str) -> None:
        await self._run(["--chip", chip, "--port", self.port, "erase-flash"], what="erasing the flash")

    async def write(
        self, chip: str, baud: int, offset: int, image: str, on_progress: Callable[[float], None]
    ) -> None:
        def on_line(line: str) -> None:
            percent = parse_progress(line)
            if percent is not None:
                on_progress(percent)

        await self._run(
            [
                "--chip",
                chip,
                "--port",
                self.port,
                "--baud",
                str(baud),
                "write-flash",
                "-z",
                f"0x{offset:x}",
                image,
            ],
            on_line,
            what="writing the firmware",
        )
        on_progress(100.0)


def _failure(what: str, port: str, lines: list[str], status: int) -> str:
    fatal = [line for line in lines if "error" in line.lower()]
    detail = (fatal or lines or [f"exit status {status}"])[-1]
    hint = ""
    if "permission" in detail.lower():
        hint = (
            "; on Linux add yourself to the dialout group (sudo usermod -aG dialout $USER) and log in again"
        )
    elif "connect" in detail.lower():
        hint = "; hold BOOT while pressing RESET to enter the bootloader, or try another cable or port"
    return f"esptool failed {what} on {port}: {detail}{hint}"
