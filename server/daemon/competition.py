"""Competition mode: while it is on and any hub runs a program, nothing new is put on a hub or started
(no upload, no run on any hub, no sim run or sweep, no flashing, no servo re-ID), so a stray click, a
second laptop's page or a script cannot change a robot in the middle of a match. Stopping always
works. It also holds the match timer, so every page watching the console (a judge's, a mentor's) shows
the same clock.

The daemon enforces the lock (the page only mirrors it, greying its controls out with the same reason):
routes that start, upload, flash or re-ID depend on `unlocked(...)`, which refuses with 409
`competition_locked`.
It is a guard against accidents, not a permission: any operator may turn it off, and the audit log
says who did. The setting is kept in the database, so a console restarted mid-competition comes back
locked as it was.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass, fields, replace
from typing import Literal

from fastapi import Depends, Request

from openbricks_server.daemon.auth import Caller, require_operator
from openbricks_server.daemon.errors import ApiError
from openbricks_server.daemon.events import EventBus
from openbricks_server.daemon.store import Store, now_ms

SETTING = "competition"
DEFAULT_MATCH_S = 150  # a WRO/FLL robot round is 2 to 2.5 minutes
MIN_MATCH_S, MAX_MATCH_S = 10, 3600


@dataclass(frozen=True)
class CompetitionState:
    on: bool = False
    match_s: int = DEFAULT_MATCH_S
    match_started_ms: int | None = None  # the daemon's clock; None: the timer is not running
    changed_by: str | None = None
    changed_ms: int | None = None


class Competition:
    """The mode's state (kept in the store, announced as `competition` events) and its lock."""

    def __init__(self, store: Store, events: EventBus):
        self.store = store
        self.events = events
        saved = store.settings.get(SETTING) or {}
        known = {f.name for f in fields(CompetitionState)}
        self.state = CompetitionState(**{k: v for k, v in saved.items() if k in known})

    def change(
        self,
        who: str,
        on: bool | None = None,
        match_s: int | None = None,
        match: Literal["start", "reset"] | None = None,
    ) -> CompetitionState:
        """Apply a change (fields left None stay), keep it and announce it. Turning the mode off also
        resets the match timer; starting the timer needs the mode on."""
        state = self.state
        if on is not None:
            state = replace(state, on=on, match_started_ms=state.match_started_ms if on else None)
        if match_s is not None:
            state = replace(state, match_s=match_s)
        if match == "start":
            if not state.on:
                raise ApiError.conflict(
                    "competition_off",
                    "the match timer runs only in competition mode, which is off",
                    'turn it on first: PUT /api/competition with {"on": true}',
                )
            state = replace(state, match_started_ms=now_ms())
        elif match == "reset":
            state = replace(state, match_started_ms=None)
        self.state = replace(state, changed_by=who, changed_ms=now_ms())
        self.store.settings.put(SETTING, asdict(self.state), who)
        self.events.publish(SETTING, asdict(self.state))
        return self.state

    @staticmethod
    def running(hubs) -> list[str]:
        """The names of the hubs running a program now (whoever started it, the hub's button included)."""
        if hubs is None:
            return []
        return sorted(actor.name for actor in hubs.list() if actor.state.status == "running")

    def check(self, hubs, what: str) -> None:
        """Raise 409 `competition_locked` if `what` must wait: the mode is on and a hub runs."""
        if not self.state.on:
            return
        running = self.running(hubs)
        if not running:
            return
        names = ", ".join(running)
        verb = "is" if len(running) == 1 else "are"
        raise ApiError.conflict(
            "competition_locked",
            f"cannot {what}: competition mode locks uploads, new runs, flashing and servo re-ID while a hub "
            f"runs, and {names} {verb} running",
            "wait for the run to end or stop it (stop and STOP ALL always work); an operator can turn "
            'competition mode off with PUT /api/competition {"on": false}',
            detail={"running": running},
        )


def unlocked(what: str):
    """A dependency for a route that puts something on a hub or a servo, or starts a run: the operator
    check (so a viewer is refused with 403 first), then the competition lock. `what` names the action
    in the refusal ("upload a program"), followed by the hub the route addresses, if any."""

    async def competition_unlocked(request: Request, caller: Caller = Depends(require_operator)) -> Caller:
        ctx = request.app.state.ctx
        hub = request.path_params.get("hub")
        ctx.competition.check(ctx.hubs, f"{what} on {hub}" if hub else what)
        return caller

    return competition_unlocked
