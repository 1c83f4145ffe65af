"""A hub's console output as the daemon keeps it: lines, telemetry samples and the watch frames.

Live output arrives as bytes in arbitrary pieces; `OutputParser` cuts it into lines (a line is
handed on as soon as its newline arrives, CRLF or LF), and takes out the frames tagged with the
nonce the daemon gave the hub (`@openbricks:<nonce> <kind> <json>`: run-begin, run-end, plot).
Anything else is output, including text that merely looks like a frame: a program cannot forge a
sample or a run boundary, and nothing it prints is lost. A hub that stamps its run log also sends the
stamps (`t <ms since the run-begin stamp>` frames, openbricks.log), so a live line carries the same
`hub_ms` as the line read back from the log; a hub without them leaves `hub_ms` empty until its log is
read back.

Run logs read back from the hub (`parse_run_log`) are stamped lines: `<epoch ms> <text>`, a header
`-- run_N --`, the launcher's framing lines (started:/stopped:/...), the program's output, and the
plot frames of a watched run, whose nonce the log records (`watched: <nonce>`), so a log read back
after a restart splits output and samples exactly as the live capture did.
"""

from __future__ import annotations

import json
import re
import time
from collections.abc import Callable
from dataclasses import dataclass

from openbricks.host_protocol import FRAME_PREFIX, parse_plot
from openbricks_server.daemon.hub_events import OutputLine, RunOutcome, TelemetrySample

_HEADER = re.compile(r"^-- run_(\d+) --$")
# Lines the launcher writes to the log only (never to the console): not the program's output.
_FRAMING = ("started: ", "stopped: ", "button pressed -> stop", "estop engaged", "watcher tick starved")
_WATCHED = "watched: "
_LOG_CAPPED = "log capped at "


def now_ms() -> int:
    return int(time.time() * 1000)


def plot_sample(payload: str, hub_ms: int | None, recv_ms: int) -> TelemetrySample | None:
    """The sample in a plot frame's JSON, or None if it is not one (then the line stays output)."""
    parsed = parse_plot(payload)
    return None if parsed is None else TelemetrySample(parsed[0], parsed[1], hub_ms, recv_ms)


class OutputParser:
    """Live output of one hub: `on_lines([(text, hub_ms)])`, `on_samples(samples)`, `on_frame(kind, data)`.

    Each `feed()` reports what it completed in one call per kind, so a burst of lines becomes one
    batch for the store and the event stream.
    """

    def __init__(
        self,
        nonce: str,
        on_lines: Callable[[list[tuple[str, int | None]]], None],
        on_samples: Callable[[list[TelemetrySample]], None],
        on_frame: Callable[[str, dict], None],
    ):
        self.frame_start = f"{FRAME_PREFIX}{nonce} "
        self.on_lines = on_lines
        self.on_samples = on_samples
        self.on_frame = on_frame
        self._partial = bytearray()
        self._started_ms: int | None = None  # the run-begin frame's stamp: stamp frames count from it
        self._stamp: int | None = None  # the hub's stamp of the lines from here on

    def feed(self, data: bytes) -> None:
        self._partial += data
        if b"\n" not in data:
            return
        *complete, rest = bytes(self._partial).split(b"\n")
        self._partial = bytearray(rest)
        self._handle([line.rstrip(b"\r").decode("utf-8", "replace") for line in complete])

    def flush(self) -> None:
        """The command ended: a last line without its newline is output too."""
        if self._partial:
            text = bytes(self._partial).rstrip(b"\r").decode("utf-8", "replace")
            self._partial.clear()
            if text:
                self._handle([text])

    def _handle(self, texts: list[str]) -> None:
        lines: list[tuple[str, int | None]] = []
        samples: list[TelemetrySample] = []
        recv = now_ms()
        for text in texts:
            if not text.startswith(self.frame_start):
                lines.append((text, self._stamp))
                continue
            kind, _, payload = text[len(self.frame_start) :].partition(" ")
            if kind == "t" and payload.isdigit() and self._started_ms is not None:
                self._stamp = self._started_ms + int(payload)
                continue
            if kind == "plot":
                sample = plot_sample(payload, self._stamp, recv)
                if sample is not None:
                    samples.append(sample)
                    continue
            elif kind in ("run-begin", "run-end"):
                try:
                    data = json.loads(payload)
                except ValueError:
                    data = None
                if isinstance(data, dict):
                    # Frames end a batch: what came before them belongs before the boundary.
                    self._emit(lines, samples)
                    lines, samples = [], []
                    started = data.get("started_ms") if kind == "run-begin" else None
                    self._started_ms = started if isinstance(started, int) else None
                    self._stamp = None
                    self.on_frame(kind, data)
                    continue
            lines.append((text, self._stamp))
        self._emit(lines, samples)

    def _emit(self, lines: list[tuple[str, int | None]], samples: list[TelemetrySample]) -> None:
        if lines:
            self.on_lines(lines)
        if samples:
            self.on_samples(samples)


class LineCounter:
    """Numbers one run's output lines from 1, stamping the daemon's receive time (and keeping the
    hub's stamp, when the hub sent one)."""

    def __init__(self):
        self.count = 0
        self.last_text: str | None = None

    def number(self, stamped: list[tuple[str, int | None]]) -> list[OutputLine]:
        recv = now_ms()
        lines = []
        for text, hub_ms in stamped:
            self.count += 1
            lines.append(OutputLine(self.count, text, hub_ms, recv))
            if text.strip():
                self.last_text = text
        return lines


@dataclass
class RunLog:
    """One run-log slot read back: its key (index, started_ms), output lines and how it ended."""

    index: int
    started_ms: int
    lines: list[OutputLine]
    samples: list[TelemetrySample]
    outcome: RunOutcome | None  # None: the log has no end (the hub reset or the run is still on)
    detail: str | None
    trigger: str | None
    text: str  # as the hub keeps it, stamps and framing lines included


def _outcome(stopped: str) -> tuple[RunOutcome, str | None]:
    text = stopped[len("stopped: ") :]
    if text.startswith("finished"):
        return "finished", None
    if text.startswith("KeyboardInterrupt"):
        return "stopped", text
    return "error", text


def parse_run_log(text: str) -> RunLog | None:
    """A run log's text as a RunLog (None if it lacks the header, e.g. a foreign file)."""
    index = started = None
    lines: list[OutputLine] = []
    samples: list[TelemetrySample] = []
    outcome: RunOutcome | None = None
    detail = trigger = None
    recv = now_ms()
    last_stamp: int | None = None
    plot_start: str | None = None
    for raw in text.split("\n"):
        stamp_text, sep, body = raw.partition(" ")
        if sep and stamp_text.isdigit():
            last_stamp = int(stamp_text)
        elif raw:
            body = raw  # a line without its stamp (e.g. a traceback's continuation): the last stamp holds
        else:
            continue
        if index is None:
            match = _HEADER.match(body)
            if match is None:
                return None
            index, started = int(match.group(1)), last_stamp
            continue
        if body.startswith("started: "):
            trigger = body[len("started: ") :].split(" | ", 1)[0]
            continue
        if body.startswith("stopped: "):
            outcome, detail = _outcome(body)
            continue
        if body.startswith(_WATCHED) and plot_start is None:
            plot_start = f"{FRAME_PREFIX}{body[len(_WATCHED) :]} plot "
            continue
        if body.startswith(_FRAMING) or body.startswith(_LOG_CAPPED):
            continue
        if plot_start is not None and body.startswith(plot_start):
            sample = plot_sample(body[len(plot_start) :], last_stamp, recv)
            if sample is not None:
                samples.append(sample)
                continue
        lines.append(OutputLine(len(lines) + 1, body, last_stamp, recv))
    if index is None or started is None:
        return None
    return RunLog(index, started, lines, samples, outcome, detail, trigger, text)
