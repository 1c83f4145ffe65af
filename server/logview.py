"""Run-log text as people read it: the hub's UTC epoch-millisecond stamps shown in local time.

The hub writes `<epoch_ms> <text>` per line and knows no time zone; the host renders
`[YYYY-MM-DD HH:MM:SS.mmm] <text>` in the computer's zone. Logs arrive in chunks that may end
mid-line, so a partial line waits for its end (or for `finish()`).
"""

from __future__ import annotations

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
