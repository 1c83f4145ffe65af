"""Jobs kept as history: what was asked (kind, label, parameters, who), how it went (state, steps,
progress, message) and its result. A job the daemon did not finish (it was stopped or killed) is marked
failed at the next start, with the reason."""

from __future__ import annotations

import json

from openbricks_server.daemon.store.db import Database, now_ms

_FIELDS = (
    "job_id, kind, label, batch, who, state, progress, message, params, result, steps, created_ms, "
    "started_ms, ended_ms"
)
_JSON = ("params", "result", "steps")
OPEN_STATES = ("queued", "running")
INTERRUPTED = "the console stopped while this job ran; check the device and start it again"


class Jobs:
    def __init__(self, db: Database):
        self.db = db

    def save(self, job: dict) -> None:
        """Insert or replace the job's row (its id is its key)."""
        row = dict(job)
        for name in _JSON:
            row[name] = None if row[name] is None else json.dumps(row[name])
        names = _FIELDS.split(", ")
        with self.db.transaction() as conn:
            conn.execute(
                f"INSERT OR REPLACE INTO jobs ({_FIELDS}) VALUES ({', '.join('?' * len(names))})",
                [row[n] for n in names],
            )

    def get(self, job_id: str) -> dict | None:
        row = self.db.query_one(f"SELECT {_FIELDS} FROM jobs WHERE job_id=?", (job_id,))
        return _job(row) if row else None

    def list(
        self,
        kind: str | None = None,
        batch: str | None = None,
        limit: int = 100,
        before: str | None = None,
        state: str | None = None,
    ) -> list[dict]:
        where, args = [], []
        for column, value in (("kind", kind), ("batch", batch), ("state", state)):
            if value is not None:
                where.append(f"{column} = ?")
                args.append(value)
        if before is not None:
            where.append("job_id < ?")
            args.append(before)
        sql = f"SELECT {_FIELDS} FROM jobs" + (" WHERE " + " AND ".join(where) if where else "")
        return [_job(r) for r in self.db.query(sql + " ORDER BY job_id DESC LIMIT ?", [*args, limit])]

    def mark_interrupted(self) -> int:
        with self.db.transaction() as conn:
            return conn.execute(
                "UPDATE jobs SET state='failed', message=?, ended_ms=? WHERE state IN (?, ?)",
                (INTERRUPTED, now_ms(), *OPEN_STATES),
            ).rowcount


def _job(row) -> dict:
    data = dict(row)
    for name in _JSON:
        data[name] = None if data[name] is None else json.loads(data[name])
    return data
