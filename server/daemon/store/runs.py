"""Runs, their output lines, telemetry samples and gaps: the history the console keeps across restarts."""

from __future__ import annotations

from dataclasses import dataclass

from openbricks_server.daemon.store.db import Database

RUN_COLUMNS = (
    "run_id, hub_id, origin, program_name, program_sha256, source, slot, who, started_ms, ended_ms, "
    "outcome, detail, line_count"
)
# A run read back from a hub's run-log slot is the run seen live when hub and slot match and the start
# stamps agree within this window (the live stamp may be the daemon's clock when the hub's was unknown).
SLOT_MATCH_MS = 2_000
OUTCOMES_OPEN = "running"  # what a run without an outcome yet is called in searches


@dataclass(frozen=True)
class RunQuery:
    """A search over the history; every field narrows it, None means any."""

    hub: str | None = None  # hub id or hub name
    text: str | None = None  # words in the output (full-text) or in the program name
    since_ms: int | None = None
    until_ms: int | None = None
    outcome: str | None = None  # one of RunOutcome, or "running"
    origin: str | None = None
    program: str | None = None
    before: str | None = None  # run id: only runs older than this one (paging)
    limit: int = 50


class Runs:
    def __init__(self, db: Database):
        self.db = db

    def insert(
        self,
        run_id: str,
        hub_id: str,
        origin: str,
        started_ms: int,
        *,
        program_name: str | None = None,
        program_sha256: str | None = None,
        source: str | None = None,
        slot: int | None = None,
        who: str | None = None,
        boot_id: str | None = None,
        ended_ms: int | None = None,
        outcome: str | None = None,
        detail: str | None = None,
    ) -> None:
        with self.db.transaction() as conn:
            conn.execute(
                "INSERT INTO runs (run_id, hub_id, origin, program_name, program_sha256, source, slot, who, "
                "boot_id, started_ms, ended_ms, outcome, detail) VALUES (?,?,?,?,?,?,?,?,?,?,?,?,?)",
                (
                    run_id,
                    hub_id,
                    origin,
                    program_name,
                    program_sha256,
                    source,
                    slot,
                    who,
                    boot_id,
                    started_ms,
                    ended_ms,
                    outcome,
                    detail,
                ),
            )

    def end(self, run_id: str, outcome: str, detail: str | None, ended_ms: int) -> None:
        with self.db.transaction() as conn:
            conn.execute(
                "UPDATE runs SET outcome=?, detail=?, ended_ms=? WHERE run_id=?",
                (outcome, detail, ended_ms, run_id),
            )

    def set_slot(self, run_id: str, slot: int) -> None:
        with self.db.transaction() as conn:
            conn.execute("UPDATE runs SET slot=? WHERE run_id=?", (slot, run_id))

    def append(self, lines: list[tuple], samples: list[tuple]) -> None:
        """Output lines `(run_id, line_no, text, hub_ms, recv_ms, seq)` and telemetry samples
        `(run_id, name, value, hub_ms, recv_ms, seq)` in one transaction. A line number already stored for
        the run is kept as it was (the run log refilling a gap must not duplicate live lines)."""
        with self.db.transaction() as conn:
            if lines:
                conn.executemany(
                    "INSERT OR IGNORE INTO output_lines (run_id, line_no, text, hub_ms, recv_ms, seq) "
                    "VALUES (?,?,?,?,?,?)",
                    lines,
                )
                last: dict[str, int] = {}
                for run_id, line_no, *_ in lines:
                    last[run_id] = max(last.get(run_id, 0), line_no)
                conn.executemany(
                    "UPDATE runs SET line_count=max(line_count, ?) WHERE run_id=?",
                    [(n, r) for r, n in last.items()],
                )
            if samples:
                conn.executemany(
                    "INSERT INTO telemetry (run_id, name, value, hub_ms, recv_ms, seq) VALUES (?,?,?,?,?,?)",
                    samples,
                )

    def stamp(self, run_id: str, stamps: list[tuple[int, str, int]]) -> None:
        """The hub's own time stamps `(line_no, text, hub_ms)` from its run log, for lines captured live
        without them; a line whose text differs from the log's keeps no stamp rather than a wrong one."""
        with self.db.transaction() as conn:
            conn.executemany(
                "UPDATE output_lines SET hub_ms=? WHERE run_id=? AND line_no=? AND text=? AND hub_ms IS NULL",
                [(hub_ms, run_id, line_no, text) for line_no, text, hub_ms in stamps],
            )

    def add_gap(self, run_id: str, reason: str, since_ms: int, until_ms: int | None) -> None:
        with self.db.transaction() as conn:
            conn.execute(
                "INSERT INTO gaps (run_id, reason, since_ms, until_ms) VALUES (?,?,?,?)",
                (run_id, reason, since_ms, until_ms),
            )

    def get(self, run_id: str) -> dict | None:
        row = self.db.query_one(f"SELECT {RUN_COLUMNS} FROM runs WHERE run_id=?", (run_id,))
        return dict(row) if row else None

    def hub_of(self, run_id: str) -> str | None:
        row = self.db.query_one("SELECT hub_id FROM runs WHERE run_id=?", (run_id,))
        return row[0] if row else None

    def find_by_slot(self, hub_id: str, slot: int, started_ms: int) -> dict | None:
        """The stored run a run-log slot read back from the hub is (same hub and slot, start stamps within
        SLOT_MATCH_MS; the closest wins), or None."""
        row = self.db.query_one(
            f"SELECT {RUN_COLUMNS} FROM runs WHERE hub_id=? AND slot=? AND started_ms BETWEEN ? AND ? "
            "ORDER BY abs(started_ms - ?) LIMIT 1",
            (hub_id, slot, started_ms - SLOT_MATCH_MS, started_ms + SLOT_MATCH_MS, started_ms),
        )
        return dict(row) if row else None

    def line_numbers(self, run_id: str) -> set[int]:
        return {r[0] for r in self.db.query("SELECT line_no FROM output_lines WHERE run_id=?", (run_id,))}

    def open_runs(self) -> list[dict]:
        return [
            dict(r)
            for r in self.db.query(f"SELECT {RUN_COLUMNS} FROM runs WHERE ended_ms IS NULL ORDER BY run_id")
        ]

    def mark_interrupted(self, keep_boot: str | None, detail: str) -> int:
        """End every run still open that was not started by `keep_boot` as `interrupted`, at its last line's
        receive time (or its start): what a daemon finds after a crash or a `kill -9`."""
        with self.db.transaction() as conn:
            cursor = conn.execute(
                "UPDATE runs SET outcome='interrupted', detail=?, ended_ms=coalesce("
                "(SELECT max(recv_ms) FROM output_lines o WHERE o.run_id=runs.run_id), started_ms) "
                "WHERE ended_ms IS NULL AND (boot_id IS NOT ? OR ? IS NULL)",
                (detail, keep_boot, keep_boot),
            )
            return cursor.rowcount

    def search(self, q: RunQuery) -> list[dict]:
        where, args = [], []
        if q.hub:
            where.append("(hub_id=? OR hub_id IN (SELECT hub_id FROM hubs WHERE name=?))")
            args += [q.hub, q.hub]
        if q.text:
            where.append(
                "(run_id IN (SELECT o.run_id FROM output_fts f JOIN output_lines o ON o.id=f.rowid "
                "WHERE output_fts MATCH ?) OR program_name LIKE ? ESCAPE '\\')"
            )
            args += [fts_phrase(q.text), "%" + like_escape(q.text) + "%"]
        if q.since_ms is not None:
            where.append("started_ms >= ?")
            args.append(q.since_ms)
        if q.until_ms is not None:
            where.append("started_ms < ?")
            args.append(q.until_ms)
        if q.outcome == OUTCOMES_OPEN:
            where.append("ended_ms IS NULL")
        elif q.outcome:
            where.append("outcome=?")
            args.append(q.outcome)
        if q.origin:
            where.append("origin=?")
            args.append(q.origin)
        if q.program:
            where.append("program_name=?")
            args.append(q.program)
        if q.before:
            where.append("run_id < ?")
            args.append(q.before)
        sql = f"SELECT {RUN_COLUMNS} FROM runs"
        if where:
            sql += " WHERE " + " AND ".join(where)
        sql += " ORDER BY run_id DESC LIMIT ?"
        args.append(q.limit)
        return [dict(r) for r in self.db.query(sql, args)]

    def lines(self, run_id: str, after: int = 0, limit: int | None = None) -> list[dict]:
        sql = (
            "SELECT line_no, text, hub_ms, recv_ms FROM output_lines WHERE run_id=? AND line_no>? "
            "ORDER BY line_no"
        )
        args: list = [run_id, after]
        if limit is not None:
            sql += " LIMIT ?"
            args.append(limit)
        return [dict(r) for r in self.db.query(sql, args)]

    def telemetry(self, run_id: str, name: str | None = None) -> list[dict]:
        sql = "SELECT name, value, hub_ms, recv_ms FROM telemetry WHERE run_id=?"
        args: list = [run_id]
        if name is not None:
            sql += " AND name=?"
            args.append(name)
        return [dict(r) for r in self.db.query(sql + " ORDER BY id", args)]

    def gaps(self, run_id: str) -> list[dict]:
        return [
            dict(r)
            for r in self.db.query(
                "SELECT reason, since_ms, until_ms FROM gaps WHERE run_id=? ORDER BY id", (run_id,)
            )
        ]


def fts_phrase(text: str) -> str:
    """User text as FTS5 phrases, one per word: every word must appear; no query syntax leaks through
    (FTS5 reads its query as a C string: a NUL would cut a phrase open)."""
    words = text.replace("\x00", " ").split()
    return " ".join('"' + w.replace('"', '""') + '"' for w in words) or '""'


def like_escape(text: str) -> str:
    return text.replace("\\", "\\\\").replace("%", "\\%").replace("_", "\\_")
