"""Stored programs and their version history: a program lives in the daemon, never only in a browser."""

from __future__ import annotations

import hashlib

from openbricks_server.daemon.store.db import Database, now_ms

VERSION_COLUMNS = "p.name, v.version, v.sha256, v.size, v.created_ms, v.who"
_JOINED = "programs p JOIN program_versions v ON v.program_id=p.program_id"


def sha256_text(source: str) -> str:
    return hashlib.sha256(source.encode("utf-8")).hexdigest()


class Programs:
    def __init__(self, db: Database):
        self.db = db

    def save(self, name: str, source: str, who: str | None) -> tuple[dict, bool]:
        """Store `source` as the newest version of `name`; returns (the version, whether it is new).
        Saving the text the newest version already has adds no version."""
        digest = sha256_text(source)
        stamp = now_ms()
        with self.db.transaction() as conn:
            row = conn.execute("SELECT program_id FROM programs WHERE name=?", (name,)).fetchone()
            if row is None:
                program_id = conn.execute(
                    "INSERT INTO programs (name, created_ms, updated_ms) VALUES (?,?,?)", (name, stamp, stamp)
                ).lastrowid
                latest = None
            else:
                program_id = row[0]
                latest = conn.execute(
                    "SELECT version, sha256 FROM program_versions WHERE program_id=? "
                    "ORDER BY version DESC LIMIT 1",
                    (program_id,),
                ).fetchone()
            created = latest is None or latest["sha256"] != digest
            if created:
                version = 1 if latest is None else latest["version"] + 1
                conn.execute(
                    "INSERT INTO program_versions "
                    "(program_id, version, source, sha256, size, created_ms, who) VALUES (?,?,?,?,?,?,?)",
                    (program_id, version, source, digest, len(source.encode("utf-8")), stamp, who),
                )
                conn.execute("UPDATE programs SET updated_ms=? WHERE program_id=?", (stamp, program_id))
        return self.version(name, None), created

    def list(self) -> list[dict]:
        return [
            dict(r)
            for r in self.db.query(
                f"SELECT {VERSION_COLUMNS} FROM {_JOINED} "
                "WHERE v.version=(SELECT max(version) FROM program_versions WHERE program_id=p.program_id) "
                "ORDER BY p.name"
            )
        ]

    def version(self, name: str, version: int | None) -> dict | None:
        """One version of a program with its source (the newest when `version` is None), or None."""
        sql = f"SELECT {VERSION_COLUMNS}, v.source FROM {_JOINED} WHERE p.name=? "
        if version is None:
            row = self.db.query_one(sql + "ORDER BY v.version DESC LIMIT 1", (name,))
        else:
            row = self.db.query_one(sql + "AND v.version=?", (name, version))
        return dict(row) if row else None

    def versions(self, name: str) -> list[dict]:
        return [
            dict(r)
            for r in self.db.query(
                f"SELECT {VERSION_COLUMNS} FROM {_JOINED} WHERE p.name=? ORDER BY v.version DESC",
                (name,),
            )
        ]

    def rename(self, name: str, new_name: str) -> str:
        """Give `name` (all its versions) the name `new_name`: "renamed", or why not: "missing" (no
        program `name`) or "taken" (a program `new_name` exists). Runs keep the name they ran under."""
        with self.db.transaction() as conn:
            if conn.execute("SELECT 1 FROM programs WHERE name=?", (new_name,)).fetchone():
                return "taken"
            changed = conn.execute(
                "UPDATE programs SET name=?, updated_ms=? WHERE name=?", (new_name, now_ms(), name)
            ).rowcount
        return "renamed" if changed else "missing"

    def delete(self, name: str) -> bool:
        with self.db.transaction() as conn:
            return conn.execute("DELETE FROM programs WHERE name=?", (name,)).rowcount > 0


_DRAFT_COLUMNS = "name, source, base_version, who, updated_ms"


class Drafts:
    """The editor's unsaved text per program name, written as it is typed; saving the program clears it.

    A draft is not a version: it is never checked, never run, and one per name (the newest typing wins).
    """

    def __init__(self, db: Database):
        self.db = db

    def put(self, name: str, source: str, base_version: int | None, who: str | None) -> dict:
        stamp = now_ms()
        with self.db.transaction() as conn:
            conn.execute(
                "INSERT INTO drafts (name, source, base_version, who, updated_ms) VALUES (?,?,?,?,?) "
                "ON CONFLICT (name) DO UPDATE SET source=excluded.source, "
                "base_version=excluded.base_version, who=excluded.who, updated_ms=excluded.updated_ms",
                (name, source, base_version, who, stamp),
            )
        return {"name": name, "source": source, "base_version": base_version, "who": who, "updated_ms": stamp}

    def get(self, name: str) -> dict | None:
        row = self.db.query_one(f"SELECT {_DRAFT_COLUMNS} FROM drafts WHERE name=?", (name,))
        return dict(row) if row else None

    def list(self) -> list[dict]:
        """Every draft without its text, by name."""
        return [
            dict(r)
            for r in self.db.query("SELECT name, base_version, who, updated_ms FROM drafts ORDER BY name")
        ]

    def delete(self, name: str) -> bool:
        with self.db.transaction() as conn:
            return conn.execute("DELETE FROM drafts WHERE name=?", (name,)).rowcount > 0

    def rename(self, name: str, new_name: str) -> None:
        """A renamed program keeps its draft (one already under `new_name` gives way)."""
        with self.db.transaction() as conn:
            if conn.execute("SELECT 1 FROM drafts WHERE name=?", (name,)).fetchone():
                conn.execute("DELETE FROM drafts WHERE name=?", (new_name,))
                conn.execute("UPDATE drafts SET name=? WHERE name=?", (new_name, name))
