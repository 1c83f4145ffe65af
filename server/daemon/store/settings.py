"""Settings the console keeps across restarts, one JSON value per key (competition mode is one): a
console restarted in the middle of a competition must come back as it was, not unlocked."""

from __future__ import annotations

import json

from openbricks_server.daemon.store.db import Database, now_ms


class Settings:
    def __init__(self, db: Database):
        self.db = db

    def get(self, key: str) -> dict | None:
        row = self.db.query_one("SELECT value FROM settings WHERE key=?", (key,))
        return None if row is None else json.loads(row["value"])

    def put(self, key: str, value: dict, who: str | None) -> None:
        with self.db.transaction() as conn:
            conn.execute(
                "INSERT OR REPLACE INTO settings (key, value, who, updated_ms) VALUES (?,?,?,?)",
                (key, json.dumps(value), who, now_ms()),
            )
