"""The seam between the hub actors and the rest of the daemon (store, event stream).

A hub actor owns one link and knows nothing of SQLite or WebSockets: it reports what happens on its hub
through `HubEvents`, which the daemon core implements once (persist, then publish as an event). Keeping
this one narrow interface lets real, serial, virtual and simulated hubs share the same actor and lets the
store change without touching the link code.

Times are integer epoch milliseconds. `hub_ms` is the hub's own clock (the run-log stamp; the daemon sets
the hub's RTC on every connect), `recv_ms` the daemon's receive time.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Literal, Protocol

HubStatus = Literal["offline", "connecting", "idle", "running", "busy", "flashing"]
HubKind = Literal["ble", "serial", "virtual"]
# Started through the API, by the hub's button, read back from the run log, or a simulator run.
RunOrigin = Literal["daemon", "button", "log", "sim"]
RunOutcome = Literal["finished", "error", "stopped", "dropped", "interrupted"]


@dataclass
class HubState:
    """What the dashboard shows of one hub; `hub_id` is stable across renames (derived from kind+address)."""

    hub_id: str
    name: str
    kind: HubKind
    address: str  # BLE address, serial port or virtual hub id
    status: HubStatus = "offline"
    rssi: int | None = None
    last_seen_ms: int | None = None
    firmware: str | None = None
    capabilities: dict = field(default_factory=dict)
    staged_program: str | None = None
    run_id: str | None = None  # the current run, while one is on
    run_started_ms: int | None = None
    holder: dict | None = None  # the operation holding the hub: {"operation", "who", "since_ms"}


@dataclass
class RunStart:
    hub_id: str
    origin: RunOrigin
    started_ms: int  # hub clock when known, else the daemon's
    program_name: str | None = None
    source: str | None = None  # the exact text that ran, when the daemon staged it
    slot: int | None = None  # the hub's run-log slot, once known
    who: str | None = None  # the token's label that asked for it


@dataclass
class OutputLine:
    line_no: int  # per run, from 1, strictly increasing
    text: str  # without the line ending
    hub_ms: int | None
    recv_ms: int


@dataclass
class TelemetrySample:
    name: str
    value: float
    hub_ms: int | None
    recv_ms: int


class HubEvents(Protocol):
    """Implemented by the daemon core; called by hub actors from the event loop (never blocks)."""

    def hub_changed(self, hub: HubState) -> None:
        """Status, name, firmware or current run changed: store it in the registry and publish it."""

    def run_started(self, run: RunStart) -> str:
        """A run began (live or recovered): returns its sortable run id."""

    def run_output(self, run_id: str, lines: list[OutputLine]) -> None:
        """Lines of output, in order; persisted within 50 ms."""

    def run_telemetry(self, run_id: str, samples: list[TelemetrySample]) -> None:
        """Samples of `openbricks.tools.plot(name, value)` (or the simulator's pose and speeds)."""

    def run_gap(self, run_id: str, reason: str, since_ms: int, until_ms: int | None) -> None:
        """The link dropped mid-run: output may be missing for this span until the run log refills it."""

    def run_ended(self, run_id: str, outcome: RunOutcome, detail: str | None, ended_ms: int) -> None:
        """The run is over; `detail` is the error line or the stop reason."""

    def run_log_read(
        self,
        hub_id: str,
        slot: int,
        started_ms: int,
        lines: list[OutputLine],
        outcome: RunOutcome = "finished",
        detail: str | None = None,
    ) -> None:
        """A run-log slot read back from the hub: the core matches it to a stored run by
        (hub, slot, started_ms), fills what live capture missed, or stores it as a run of origin "log"
        that ended with `outcome` (the log's last line: finished, stopped, error with `detail`, or
        interrupted when the log has no end: the hub reset or lost power mid-run)."""
