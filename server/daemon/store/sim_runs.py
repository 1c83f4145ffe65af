"""Simulator runs: the job's inputs, its state, result and recording, beside the run's row in `runs`.

JSON columns (`start_mm_deg`, `pose`, `score`) are decoded on the way out; `recording` is a path
relative to the data dir.
"""

from __future__ import annotations

import json

from openbricks_server.daemon.store.db import Database

_JSON = ("start_mm_deg", "pose", "score")
COLUMNS = (
    "s.run_id, s.world, s.chassis, s.seed, s.start_mm_deg, s.speed, s.limit_ms, s.wall_limit_s, "
    "s.memory_mb, s.state, s.exit, s.sim_ms, s.pose, s.score, s.error, s.recording, "
    "r.program_name, r.program_sha256, r.who, r.started_ms, r.ended_ms"
)
_JOINED = "sim_runs s JOIN runs r ON r.run_id=s.run_id"
OPEN_STATES = ("queued", "running")


def _decoded(row) -> dict:
    out = dict(row)
    for key in _JSON:
        if out[key] is not None:
            out[key] = json.loads(out[key])
    return out


class SimRuns:
    def __init__(self, db: Database):
        self.db = db

    def insert(self, run_id: str, job: dict) -> None:
        """A sim run queued with `job`'s inputs (its `runs` row must exist)."""
        start = job.get("start_mm_deg")
        with self.db.transaction() as conn:
            conn.execute(
                "INSERT INTO sim_runs (run_id, world, chassis, seed, start_mm_deg, speed, limit_ms, "
                "wall_limit_s, memory_mb, state) VALUES (?,?,?,?,?,?,?,?,?, 'queued')",
                (
                    run_id,
                    job["world"],
                    job.get("chassis"),
                    job["seed"],
                    None if start is None else json.dumps(list(start)),
                    job.get("speed"),
                    job["limit_ms"],
                    job["wall_limit_s"],
                    job["memory_mb"],
                ),
            )

    def update(self, run_id: str, **fields) -> None:
        """Set state, chassis, exit, sim_ms, pose, score, error or recording."""
        if not fields:
            return
        for key in _JSON:
            if key in fields and fields[key] is not None:
                fields[key] = json.dumps(fields[key])
        assignments = ", ".join(f"{key}=?" for key in fields)
        with self.db.transaction() as conn:
            conn.execute(f"UPDATE sim_runs SET {assignments} WHERE run_id=?", (*fields.values(), run_id))

    def get(self, run_id: str) -> dict | None:
        row = self.db.query_one(f"SELECT {COLUMNS} FROM {_JOINED} WHERE s.run_id=?", (run_id,))
        return _decoded(row) if row else None

    def list(self, before: str | None = None, limit: int = 50) -> list[dict]:
        sql, args = f"SELECT {COLUMNS} FROM {_JOINED}", []
        if before is not None:
            sql += " WHERE s.run_id < ?"
            args.append(before)
        sql += " ORDER BY s.run_id DESC LIMIT ?"
        args.append(limit)
        return [_decoded(r) for r in self.db.query(sql, args)]

    def mark_failed_open(self, error: str) -> int:
        """Runs left queued or running by a daemon that stopped without ending them: failed, with why."""
        with self.db.transaction() as conn:
            return conn.execute(
                "UPDATE sim_runs SET state='failed', error=coalesce(error, ?) WHERE state IN (?, ?)",
                (error, *OPEN_STATES),
            ).rowcount
