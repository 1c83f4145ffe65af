"""The hub registry: every hub the daemon has seen, with its last known state."""

from __future__ import annotations

import json
from dataclasses import asdict

from openbricks_server.daemon.hub_events import HubState
from openbricks_server.daemon.store.db import Database, now_ms

_FIELDS = (
    "hub_id, name, kind, address, status, rssi, last_seen_ms, firmware, capabilities, staged_program, "
    "run_id, run_started_ms, holder"
)


class Hubs:
    def __init__(self, db: Database):
        self.db = db

    def upsert(self, hub: HubState) -> None:
        row = asdict(hub)
        row["capabilities"] = json.dumps(row["capabilities"])
        row["holder"] = json.dumps(row["holder"]) if row["holder"] is not None else None
        names = _FIELDS.split(", ")
        with self.db.transaction() as conn:
            conn.execute(
                f"INSERT INTO hubs ({_FIELDS}, updated_ms) VALUES ({', '.join('?' * len(names))}, ?) "
                "ON CONFLICT (hub_id) DO UPDATE SET "
                + ", ".join(f"{n}=excluded.{n}" for n in names[1:])
                + ", updated_ms=excluded.updated_ms",
                [row[n] for n in names] + [now_ms()],
            )

    def list(self) -> list[HubState]:
        return [_state(r) for r in self.db.query(f"SELECT {_FIELDS} FROM hubs ORDER BY name, hub_id")]

    def get(self, hub_id: str) -> HubState | None:
        row = self.db.query_one(f"SELECT {_FIELDS} FROM hubs WHERE hub_id=?", (hub_id,))
        return _state(row) if row else None

    def mark_all_offline(self) -> None:
        """At start-up no link is open yet, whatever the registry said when the last daemon stopped."""
        with self.db.transaction() as conn:
            conn.execute(
                "UPDATE hubs SET status='offline', run_id=NULL, run_started_ms=NULL, holder=NULL "
                "WHERE status != 'offline' OR run_id IS NOT NULL OR holder IS NOT NULL"
            )


def _state(row) -> HubState:
    data = dict(row)
    data["capabilities"] = json.loads(data["capabilities"] or "{}")
    data["holder"] = json.loads(data["holder"]) if data["holder"] else None
    return HubState(**data)
