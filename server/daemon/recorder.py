"""The daemon core's side of the `HubEvents` seam: what a hub actor reports is stored, then published.

Hub and run state changes are written at once (they are rare and a client may read them back right away).
Output lines and telemetry samples are published at once and written in small batches by `flush_loop`
within `flush_interval_s` (20 ms by default), so a `kill -9` loses at most that window, and the hub's own
run-log slot fills it in on the next connect (`run_log_read`).
"""

from __future__ import annotations

import asyncio
import logging
import threading
from dataclasses import asdict

from ulid import ULID

from openbricks_server.daemon.events import EventBus
from openbricks_server.daemon.hub_events import (
    HubState,
    OutputLine,
    RunOutcome,
    RunStart,
    TelemetrySample,
)
from openbricks_server.daemon.store import Store, now_ms, sha256_text

log = logging.getLogger("openbricks.console")

INTERRUPTED_BY_CRASH = "the daemon stopped during the run (crash, kill or power loss); output may end early"
INTERRUPTED_BY_STOP = "the daemon was shut down during the run"
FROM_RUN_LOG = "read back from the hub's run log"


class UnknownRun(KeyError):
    """A hub actor reported for a run id the daemon never gave out (a bug in the caller)."""


def _line(line: OutputLine) -> dict:
    return {"line_no": line.line_no, "text": line.text, "hub_ms": line.hub_ms, "recv_ms": line.recv_ms}


class Recorder:
    """Implements `openbricks_server.daemon.hub_events.HubEvents`."""

    def __init__(self, store: Store, bus: EventBus, flush_interval_s: float):
        self.store = store
        self.bus = bus
        self.flush_interval_s = flush_interval_s
        self._hub_of_run: dict[str, str] = {}  # runs that have not ended yet
        self._lines: list[tuple] = []
        self._samples: list[tuple] = []
        self._pending = asyncio.Event()
        self._writing = threading.Lock()  # held from taking the pending lines until they are committed
        bus.before_store_read = self.flush

    # -- HubEvents ---------------------------------------------------------------------------------------

    def hub_changed(self, hub: HubState) -> None:
        self.store.hubs.upsert(hub)
        self.bus.publish("hub", asdict(hub), hub=hub.hub_id, run=hub.run_id)

    def run_started(self, run: RunStart) -> str:
        run_id = str(ULID())
        self.store.runs.insert(
            run_id,
            run.hub_id,
            run.origin,
            run.started_ms,
            program_name=run.program_name,
            program_sha256=sha256_text(run.source) if run.source is not None else None,
            source=run.source,
            slot=run.slot,
            who=run.who,
            boot_id=self.bus.boot_id,
        )
        self._hub_of_run[run_id] = run.hub_id
        self.bus.publish("run_started", self.store.runs.get(run_id), hub=run.hub_id, run=run_id)
        return run_id

    def run_output(self, run_id: str, lines: list[OutputLine]) -> None:
        if not lines:
            return
        hub = self._hub(run_id)
        seq = self.bus.next_seq()
        self._lines.extend((run_id, ln.line_no, ln.text, ln.hub_ms, ln.recv_ms, seq) for ln in lines)
        self._pending.set()
        data = {"lines": [_line(ln) for ln in lines]}
        self.bus.publish("output", data, hub=hub, run=run_id, ts=lines[-1].recv_ms, persist=False, seq=seq)

    def run_telemetry(self, run_id: str, samples: list[TelemetrySample]) -> None:
        if not samples:
            return
        hub = self._hub(run_id)
        seq = self.bus.next_seq()
        self._samples.extend((run_id, s.name, s.value, s.hub_ms, s.recv_ms, seq) for s in samples)
        self._pending.set()
        data = {
            "samples": [
                {"name": s.name, "value": s.value, "hub_ms": s.hub_ms, "recv_ms": s.recv_ms} for s in samples
            ]
        }
        self.bus.publish(
            "telemetry", data, hub=hub, run=run_id, ts=samples[-1].recv_ms, persist=False, seq=seq
        )

    def run_gap(self, run_id: str, reason: str, since_ms: int, until_ms: int | None) -> None:
        hub = self._hub(run_id)
        self.store.runs.add_gap(run_id, reason, since_ms, until_ms)
        data = {"reason": reason, "since_ms": since_ms, "until_ms": until_ms}
        self.bus.publish("run_gap", data, hub=hub, run=run_id)

    def run_ended(self, run_id: str, outcome: RunOutcome, detail: str | None, ended_ms: int) -> None:
        hub = self._hub(run_id)
        self.flush()
        self.store.runs.end(run_id, outcome, detail, ended_ms)
        self._hub_of_run.pop(run_id, None)
        self.bus.publish("run_ended", self.store.runs.get(run_id), hub=hub, run=run_id)

    def run_log_read(
        self,
        hub_id: str,
        slot: int,
        started_ms: int,
        lines: list[OutputLine],
        outcome: RunOutcome = "finished",
        detail: str | None = None,
    ) -> None:
        self.flush()
        run = self.store.runs.find_by_slot(hub_id, slot, started_ms)
        if run is None:
            ended_ms = max([started_ms] + [ln.hub_ms for ln in lines if ln.hub_ms is not None])
            run_id = str(ULID.from_timestamp(started_ms / 1000))
            self.store.runs.insert(
                run_id,
                hub_id,
                "log",
                started_ms,
                slot=slot,
                boot_id=self.bus.boot_id,
                ended_ms=ended_ms,
                outcome=outcome,
                detail=f"{detail} ({FROM_RUN_LOG})" if detail else FROM_RUN_LOG,
            )
            self.bus.publish("run_started", self.store.runs.get(run_id), hub=hub_id, run=run_id)
            missing = lines
        else:
            run_id = run["run_id"]
            have = self.store.runs.line_numbers(run_id)
            missing = [ln for ln in lines if ln.line_no not in have]
            self.store.runs.stamp(
                run_id, [(ln.line_no, ln.text, ln.hub_ms) for ln in lines if ln.line_no in have and ln.hub_ms]
            )
        if missing:
            seq = self.bus.next_seq()
            self.store.runs.append(
                [(run_id, ln.line_no, ln.text, ln.hub_ms, ln.recv_ms, seq) for ln in missing], []
            )
            data = {"lines": [_line(ln) for ln in missing], "from_run_log": True}
            self.bus.publish("output", data, hub=hub_id, run=run_id, persist=False, seq=seq)
        if run is None:
            self.bus.publish("run_ended", self.store.runs.get(run_id), hub=hub_id, run=run_id)

    # -- the core's own -----------------------------------------------------------------------------------

    def _hub(self, run_id: str) -> str:
        hub = self._hub_of_run.get(run_id) or self.store.runs.hub_of(run_id)
        if hub is None:
            raise UnknownRun(run_id)
        return hub

    def flush(self) -> None:
        """Write the pending output lines and samples in one transaction (any thread).

        On return everything published so far is in the database, including lines a background write
        had already taken: a reader of the store (a client catching up) must never miss them."""
        with self._writing:
            if not self._lines and not self._samples:
                return
            lines, samples = self._lines, self._samples
            self._lines, self._samples = [], []
            try:
                self.store.runs.append(lines, samples)
            except BaseException:
                self._lines[:0], self._samples[:0] = lines, samples  # kept for the next attempt
                raise

    async def flush_loop(self) -> None:
        """Write pending output at most `flush_interval_s` after it arrived; sleeps while nothing does.

        The write runs in a worker thread: a commit that waits on the disk (a WAL checkpoint) must not
        hold up the event loop, which meanwhile delivers live output to every client."""
        while True:
            await self._pending.wait()
            await asyncio.sleep(self.flush_interval_s)
            self._pending.clear()
            try:
                await asyncio.to_thread(self.flush)
            except Exception:
                log.exception("could not write output lines to the database; retrying")
                self._pending.set()

    def close(self) -> None:
        """The daemon stops: write what is pending and end the runs still open as interrupted."""
        self.flush()
        for run_id in list(self._hub_of_run):
            self.run_ended(run_id, "interrupted", INTERRUPTED_BY_STOP, now_ms())
