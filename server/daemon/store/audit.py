"""The audit log: who (token label and role) did what (method and path) when, and how it ended."""

from __future__ import annotations

from openbricks_server.daemon.store.db import Database, now_ms


class Audit:
    def __init__(self, db: Database):
        self.db = db

    def add(self, who: str, role: str, action: str, status: int) -> None:
        with self.db.transaction() as conn:
            conn.execute(
                "INSERT INTO audit (ts_ms, who, role, action, status) VALUES (?,?,?,?,?)",
                (now_ms(), who, role, action, status),
            )

    def list(self, limit: int = 100, before_id: int | None = None) -> list[dict]:
        sql = "SELECT id, ts_ms, who, role, action, status FROM audit"
        args: list = []
        if before_id is not None:
            sql += " WHERE id < ?"
            args.append(before_id)
        args.append(limit)
        return [dict(r) for r in self.db.query(sql + " ORDER BY id DESC LIMIT ?", args)]
