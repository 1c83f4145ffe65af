"""Access tokens minted with `openbricks console token`: only their SHA-256 is stored.

A token is shown once, when minted; the database alone cannot be used to sign in.
"""

from __future__ import annotations

import hashlib
import secrets
import sqlite3

from openbricks_server.daemon.store.db import Database, now_ms

ROLES = ("viewer", "operator")


def token_hash(token: str) -> str:
    return hashlib.sha256(token.encode("utf-8", "surrogateescape")).hexdigest()


def new_token() -> str:
    """A random token that never starts with "-": a script's `--token TOKEN` would read one that did
    as an option (argparse refuses it), so about one token in 64 could not be passed as people pass it."""
    while True:
        token = secrets.token_urlsafe(32)
        if not token.startswith("-"):
            return token


class LabelTaken(Exception):
    pass


class Tokens:
    def __init__(self, db: Database):
        self.db = db

    def mint(self, role: str, label: str) -> str:
        """A new token for `role`, known by `label` in the audit log; returns the token itself."""
        if role not in ROLES:
            raise ValueError(f"role must be one of {', '.join(ROLES)}")
        token = new_token()
        try:
            with self.db.transaction() as conn:
                conn.execute(
                    "INSERT INTO tokens (token_sha256, label, role, created_ms) VALUES (?,?,?,?)",
                    (token_hash(token), label, role, now_ms()),
                )
        except sqlite3.IntegrityError:
            raise LabelTaken(label) from None
        return token

    def next_label(self, role: str) -> str:
        taken = {r[0] for r in self.db.query("SELECT label FROM tokens")}
        n = 1
        while f"{role}-{n}" in taken:
            n += 1
        return f"{role}-{n}"

    def lookup(self, token: str) -> tuple[str, str] | None:
        """(label, role) of a valid token, else None."""
        row = self.db.query_one("SELECT label, role FROM tokens WHERE token_sha256=?", (token_hash(token),))
        return (row[0], row[1]) if row else None

    def list(self) -> list[dict]:
        return [
            dict(r) for r in self.db.query("SELECT label, role, created_ms FROM tokens ORDER BY created_ms")
        ]

    def revoke(self, label: str) -> bool:
        with self.db.transaction() as conn:
            return conn.execute("DELETE FROM tokens WHERE label=?", (label,)).rowcount > 0

    def any(self) -> bool:
        return self.db.query_one("SELECT 1 FROM tokens LIMIT 1") is not None
