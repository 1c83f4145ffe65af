"""Run-log text as people read it: the hub's UTC epoch-millisecond stamps shown in local time.

The hub writes `<epoch_ms> <text>` per line and knows no time zone; the host renders
`[YYYY-MM-DD HH:MM:SS.mmm] <text>` in the computer's zone. Logs arrive in chunks that may end
mid-line, so a partial line waits for its end (or for `finish()`).
"""

from __future__ import annotations

import json
import re
from collections.abc import Callable
from datetime import datetime

_STAMPED = re.compile(r"^(\d{9,16}) (.*)$", re.DOTALL)


def local_time(epoch_ms: int) -> str:
    moment = datetime.fromtimestamp(epoch_ms / 1000).astimezone()
    return moment.strftime("%Y-%m-%d %H:%M:%S.") + f"{epoch_ms % 1000:03d}"


def render_line(line: str) -> str:
    stamped = _STAMPED.match(line)
    if not stamped:
        return line
    return f"[{local_time(int(stamped.group(1)))}] {stamped.group(2)}"


class LogRenderer:
    """Feed chunks of log text; whole lines come out rendered through `emit`."""

    def __init__(self, emit: Callable[[str], None]):
        self._emit = emit
        self._partial = ""

    def feed(self, text: str) -> None:
        lines = (self._partial + text).split("\n")
        self._partial = lines.pop()
        for line in lines:
            self._emit(render_line(line.rstrip("\r")) + "\n")

    def finish(self) -> None:
        if self._partial:
            self._emit(render_line(self._partial.rstrip("\r")) + "\n")
            self._partial = ""


def _span(indices: list[int]) -> str:
    if indices == list(range(indices[0], indices[-1] + 1)) and len(indices) > 2:
        return f"{indices[0]}..{indices[-1]}"
    return ", ".join(str(i) for i in indices)


def missing_run(name: str, index: int, indices: list[int], slots: int) -> str:
    """Why run `index` can't be shown: never happened, overwritten, or lost; with what can be shown."""
    if not indices:
        return f"{name} has no run {index}: it has no run logs yet (runs are logged when a program runs)"
    kept = f"runs you can show: {_span(indices)}"
    if index > indices[-1]:
        return f"{name} has no run {index}: no such run exists yet (the newest is run {indices[-1]}); {kept}"
    if index < indices[0]:
        return f"run {index} of {name} was overwritten: a hub keeps only its last {slots} runs; {kept}"
    return f"{name} has no log of run {index} (its slot was reused or removed); {kept}"


# Lines the launcher writes into a run log itself (never on the console): the rest is the program's.
LAUNCHER_LINES = (
    "-- run_",
    "started: ",
    "stopped: ",
    "button pressed -> stop",
    "estop engaged",
    "log capped at ",
    "watcher tick starved",
    "watched: ",
    "a motor halt",
    "native scheduler reset failed",
)


def print_runs(name: str, runs: list[dict], as_json: bool) -> None:
    """`log --list`: one line per kept run, or with --json one array of {"index", "bytes"} objects."""
    if as_json:
        print(json.dumps([{"index": entry["index"], "bytes": entry["bytes"]} for entry in runs]))
        return
    if not runs:
        print(f"{name} has no run logs yet")
    for entry in runs:
        print(f"run {entry['index']:>4}  {entry['bytes']:>7} bytes")


def program_lines(log_text: str) -> list[str]:
    """The lines a run's program put on the console, from its run log: stamps off, the launcher's
    own lines left out."""
    lines = []
    for line in log_text.split("\n"):
        stamped = _STAMPED.match(line.rstrip("\r"))
        if not stamped:
            continue
        text = stamped.group(2)
        if not text.startswith(LAUNCHER_LINES):
            lines.append(text)
    return lines
