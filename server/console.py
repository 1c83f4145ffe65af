"""Terminal output shared by the commands: step lines, a progress bar, a yes/no question.

Steps and progress go to stderr so a command's stdout carries only its data (a program's output, a
log, a list), which scripts can pipe. The bar redraws in place on a terminal and prints a line per
tenth otherwise, so CI logs and pipes stay readable. Colour follows rich's rules, NO_COLOR among them.
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
    """A 0..100 % bar; `update(percent)` as often as you like, `finish()` once.

    On a terminal it is rich's bar (which leaves colour out under NO_COLOR or a dumb terminal);
    elsewhere a line per tenth, which a log or a pipe keeps readable."""

    def __init__(self, label: str, stream: TextIO | None = None):
        self.label = label
        self.stream = stream or sys.stderr
        self.interactive = self.stream.isatty()
        self._shown = -1.0
        self._bar = None
        if self.interactive:
            from rich.console import Console
            from rich.progress import BarColumn, Progress, TaskProgressColumn, TextColumn

            columns = (TextColumn(f"    {label}"), BarColumn(), TaskProgressColumn())
            self._bar = Progress(*columns, console=Console(file=self.stream))
            self._task = self._bar.add_task(label, total=100.0)
            self._bar.start()

    def update(self, percent: float) -> None:
        percent = max(0.0, min(100.0, percent))
        if self._bar is not None:
            self._bar.update(self._task, completed=percent)
            self._shown = percent
        elif int(percent // 10) > int(self._shown // 10) or (percent == 100 and self._shown < 100):
            self.stream.write(f"    {self.label} {int(percent // 10) * 10:3d} %\n")
            self.stream.flush()
            self._shown = percent

    def finish(self) -> None:
        if self._shown < 100:
            self.update(100.0)
        if self._bar is not None:
            self._bar.stop()


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
