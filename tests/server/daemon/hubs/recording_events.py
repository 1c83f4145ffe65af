"""HubEvents that records what the actors report, for the actor tests (the daemon tests use the store)."""

from __future__ import annotations

import asyncio
import itertools
from dataclasses import dataclass, field

from openbricks_server.daemon.hub_events import HubState, OutputLine, RunStart, TelemetrySample


@dataclass
class RecordedRun:
    start: RunStart
    lines: list[OutputLine] = field(default_factory=list)
    samples: list[TelemetrySample] = field(default_factory=list)
    gaps: list[tuple] = field(default_factory=list)
    ended: tuple | None = None

    @property
    def texts(self) -> list[str]:
        return [line.text for line in self.lines]


class RecordingEvents:
    def __init__(self):
        self.states: list[HubState] = []
        self.runs: dict[str, RecordedRun] = {}
        self.logs: list[tuple] = []
        self._ids = itertools.count(1)
        self.changed = asyncio.Event()

    def _poke(self) -> None:
        self.changed.set()
        self.changed = asyncio.Event()

    def hub_changed(self, hub: HubState) -> None:
        self.states.append(hub)
        self._poke()

    def run_started(self, run: RunStart) -> str:
        run_id = f"run-{next(self._ids)}"
        self.runs[run_id] = RecordedRun(run)
        self._poke()
        return run_id

    def run_output(self, run_id, lines):
        self.runs[run_id].lines.extend(lines)
        self._poke()

    def run_telemetry(self, run_id, samples):
        self.runs[run_id].samples.extend(samples)
        self._poke()

    def run_gap(self, run_id, reason, since_ms, until_ms):
        self.runs[run_id].gaps.append((reason, since_ms, until_ms))
        self._poke()

    def run_ended(self, run_id, outcome, detail, ended_ms):
        self.runs[run_id].ended = (outcome, detail, ended_ms)
        self._poke()

    def run_log_read(self, hub_id, slot, started_ms, lines, outcome="finished", detail=None):
        self.logs.append((hub_id, slot, started_ms, lines, outcome, detail))
        self._poke()

    def statuses(self, hub_id: str) -> list[str]:
        seen = [state.status for state in self.states if state.hub_id == hub_id]
        return [s for i, s in enumerate(seen) if i == 0 or seen[i - 1] != s]

    async def until(self, predicate, timeout_s: float = 20.0):
        async with asyncio.timeout(timeout_s):
            while not predicate():
                await self.changed.wait()
