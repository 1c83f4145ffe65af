"""Terminal output shared by the commands: step lines, a progress bar, a yes/no question.

Steps and progress go to stderr so a command's stdout carries only its data (a program's output, a
log, a list), which scripts can pipe. The bar redraws in place on a terminal and prints a line per
tenth otherwise, so CI logs and pipes stay readable.
"""

from __future__ import annotations

import sys
from typing import TextIO

from openbricks_server.errors import CliError


class Steps:
    """`step("erase")`-style lines on stderr; `detail` lines only with --verbose."""

    def __init__(self, verbose: bool = False, stream: TextIO | None = None):
        self.verbose = verbose
        self.stream = stream or sys.stderr

    def step(self, text: str) -> None:
        print(f"==> {text}", file=self.stream, flush=True)

    def note(self, text: str) -> None:
        print(f"    {text}", file=self.stream, flush=True)

    def detail(self, text: str) -> None:
        if self.verbose:
            print(f"    {text}", file=self.stream, flush=True)


class ProgressBar:
    """A 0..100 % bar; `update(percent)` as often as you like, `finish()` once."""

    WIDTH = 30

    def __init__(self, label: str, stream: TextIO | None = None):
        self.label = label
        self.stream = stream or sys.stderr
        self.interactive = self.stream.isatty()
        self._shown = -1.0

    def update(self, percent: float) -> None:
        percent = max(0.0, min(100.0, percent))
        if self.interactive:
            filled = int(self.WIDTH * percent / 100)
            bar = "#" * filled + "." * (self.WIDTH - filled)
            self.stream.write(f"\r    {self.label} [{bar}] {percent:5.1f} %")
            self.stream.flush()
            self._shown = percent
        elif int(percent // 10) > int(self._shown // 10) or (percent == 100 and self._shown < 100):
            self.stream.write(f"    {self.label} {int(percent // 10) * 10:3d} %\n")
            self.stream.flush()
            self._shown = percent

    def finish(self) -> None:
        if self._shown < 100:
            self.update(100.0)
        if self.interactive:
            self.stream.write("\n")
            self.stream.flush()


def confirm(question: str, assume_yes: bool, hint: str) -> None:
    """Ask `question`; go on only on yes. Without a terminal to ask, refuse with `hint` (e.g. --yes)."""
    if assume_yes:
        return
    if not sys.stdin.isatty():
        raise CliError(f"{question} No terminal to ask on: {hint}")
    try:
        answer = input(f"{question} [y/N] ").strip().lower()
    except EOFError:
        answer = ""
    if answer not in ("y", "yes"):
        raise CliError("cancelled; nothing was changed")
