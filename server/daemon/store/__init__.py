"""The console's database: one SQLite file (WAL) under the data dir, one module per kind of record.

`Store(path)` opens (and migrates) it; its attributes are the tables' APIs: `hubs`, `programs`,
`drafts`, `runs`, `events`, `tokens`, `audit`, `sim_runs`, `jobs`, `settings`. Safe to call from the
event loop and from worker threads.
"""

from __future__ import annotations

from pathlib import Path

from openbricks_server.daemon.store.audit import Audit
from openbricks_server.daemon.store.db import Database, StoreError, now_ms
from openbricks_server.daemon.store.events import StoredEvents
from openbricks_server.daemon.store.hubs import Hubs
from openbricks_server.daemon.store.jobs import Jobs
from openbricks_server.daemon.store.programs import Drafts, Programs, sha256_text
from openbricks_server.daemon.store.runs import RunQuery, Runs
from openbricks_server.daemon.store.settings import Settings
from openbricks_server.daemon.store.sim_runs import SimRuns
from openbricks_server.daemon.store.tokens import LabelTaken, Tokens

__all__ = ["LabelTaken", "RunQuery", "Store", "StoreError", "now_ms", "sha256_text"]


class Store:
    def __init__(self, path: Path):
        self.db = Database(path)
        self.hubs = Hubs(self.db)
        self.programs = Programs(self.db)
        self.drafts = Drafts(self.db)
        self.runs = Runs(self.db)
        self.events = StoredEvents(self.db)
        self.tokens = Tokens(self.db)
        self.audit = Audit(self.db)
        self.sim_runs = SimRuns(self.db)
        self.jobs = Jobs(self.db)
        self.settings = Settings(self.db)

    @property
    def path(self) -> Path:
        return self.db.path

    def close(self) -> None:
        self.db.close()
