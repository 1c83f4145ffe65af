"""The event stream's memory in the database: what a client that fell past the in-memory ring is
replayed from, and the daemon's lifetimes (boots) that sequence numbers are counted in.

Hub, run and program events are stored here as published; output lines and telemetry samples are not
stored twice: they carry the `seq` they were published under in their own tables, and are turned back
into the same envelopes when replayed.
"""

from __future__ import annotations

import json

from openbricks_server.daemon.store.db import Database, now_ms

# How long hub/run/program events stay replayable; older ones only matter to nobody.
EVENTS_KEPT_MS = 7 * 24 * 3600 * 1000


class StoredEvents:
    def __init__(self, db: Database):
        self.db = db

    def add(self, seq: int, type_: str, hub: str | None, run: str | None, ts: int, data: dict) -> None:
        with self.db.transaction() as conn:
            conn.execute(
                "INSERT INTO events (seq, type, hub, run, ts, data) VALUES (?,?,?,?,?,?)",
                (seq, type_, hub, run, ts, json.dumps(data, separators=(",", ":"))),
            )

    def max_seq(self) -> int:
        row = self.db.query_one(
            "SELECT max(coalesce((SELECT max(seq) FROM events), 0), "
            "coalesce((SELECT seq FROM output_lines WHERE seq IS NOT NULL ORDER BY seq DESC LIMIT 1), 0), "
            "coalesce((SELECT seq FROM telemetry WHERE seq IS NOT NULL ORDER BY seq DESC LIMIT 1), 0), "
            "coalesce((SELECT max(first_seq) FROM boots), 0))"
        )
        return int(row[0])

    def begin_boot(self, boot_id: str) -> int:
        """Record a new daemon lifetime; returns its first sequence number (after every stored one, so a
        client of an earlier lifetime can be replayed across the restart)."""
        first_seq = self.max_seq() + 1
        with self.db.transaction() as conn:
            conn.execute(
                "INSERT INTO boots (boot_id, started_ms, first_seq) VALUES (?,?,?)",
                (boot_id, now_ms(), first_seq),
            )
            conn.execute("DELETE FROM events WHERE ts < ?", (now_ms() - EVENTS_KEPT_MS,))
        return first_seq

    def end_boot(self, boot_id: str) -> None:
        with self.db.transaction() as conn:
            conn.execute("UPDATE boots SET ended_ms=? WHERE boot_id=?", (now_ms(), boot_id))

    def boot_first_seq(self, boot_id: str) -> int | None:
        row = self.db.query_one("SELECT first_seq FROM boots WHERE boot_id=?", (boot_id,))
        return row[0] if row else None

    def between(self, after: int, upto: int) -> list[dict]:
        """Stored envelopes with `after < seq <= upto`, in order (callers keep the window small: sequence
        numbers are contiguous, so `upto - after` bounds the work)."""
        found: dict[int, dict] = {}
        for r in self.db.query(
            "SELECT seq, type, hub, run, ts, data FROM events WHERE seq > ? AND seq <= ?",
            (after, upto),
        ):
            found[r["seq"]] = {
                "seq": r["seq"],
                "type": r["type"],
                "hub": r["hub"],
                "run": r["run"],
                "ts": r["ts"],
                "data": json.loads(r["data"]),
            }
        for r in self.db.query(
            "SELECT o.seq, o.run_id, r.hub_id, o.line_no, o.text, o.hub_ms, o.recv_ms FROM output_lines o "
            "JOIN runs r ON r.run_id=o.run_id WHERE o.seq > ? AND o.seq <= ? ORDER BY o.seq, o.line_no",
            (after, upto),
        ):
            event = found.get(r["seq"])
            if event is None:
                event = found[r["seq"]] = {
                    "seq": r["seq"],
                    "type": "output",
                    "hub": r["hub_id"],
                    "run": r["run_id"],
                    "ts": r["recv_ms"],
                    "data": {"lines": []},
                }
            line = {
                "line_no": r["line_no"],
                "text": r["text"],
                "hub_ms": r["hub_ms"],
                "recv_ms": r["recv_ms"],
            }
            event["data"]["lines"].append(line)
            event["ts"] = max(event["ts"], r["recv_ms"])
        for r in self.db.query(
            "SELECT t.seq, t.run_id, r.hub_id, t.name, t.value, t.hub_ms, t.recv_ms FROM telemetry t "
            "JOIN runs r ON r.run_id=t.run_id WHERE t.seq > ? AND t.seq <= ? ORDER BY t.seq, t.id",
            (after, upto),
        ):
            event = found.get(r["seq"])
            if event is None:
                event = found[r["seq"]] = {
                    "seq": r["seq"],
                    "type": "telemetry",
                    "hub": r["hub_id"],
                    "run": r["run_id"],
                    "ts": r["recv_ms"],
                    "data": {"samples": []},
                }
            sample = {"name": r["name"], "value": r["value"], "hub_ms": r["hub_ms"], "recv_ms": r["recv_ms"]}
            event["data"]["samples"].append(sample)
            event["ts"] = max(event["ts"], r["recv_ms"])
        return [found[s] for s in sorted(found)]
