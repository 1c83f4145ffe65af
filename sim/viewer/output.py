"""The last lines a program printed, kept for the viewer's output panel.

The program's thread writes (print() arrives as pieces: the text, then "\\n"), the viewer's thread
reads a few times a second; a version number tells the reader whether anything changed since it
last drew the panel, so an idle run sends nothing to the browsers.
"""

from __future__ import annotations

import threading
from collections import deque

DEFAULT_MAX_LINES = 400


class OutputTail:
    def __init__(self, max_lines: int = DEFAULT_MAX_LINES):
        self._lines = deque(maxlen=max_lines)
        self._partial = ""  # text after the last newline: shown, but still growing
        self._lock = threading.Lock()
        self.version = 0

    def write(self, text: str) -> int:
        """Append program output (a file-like write: returns the length written)."""
        if not text:
            return 0
        with self._lock:
            pieces = (self._partial + text).split("\n")
            self._partial = pieces.pop()
            self._lines.extend(pieces)
            self.version += 1
        return len(text)

    def clear(self) -> None:
        with self._lock:
            self._lines.clear()
            self._partial = ""
            self.version += 1

    def lines(self) -> list[str]:
        with self._lock:
            return [*self._lines, self._partial] if self._partial else list(self._lines)
