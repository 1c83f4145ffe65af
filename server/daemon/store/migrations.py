"""The database schema as a list of migrations: entry N brings a database from version N to N+1.

Never edit a released entry; append a new one. `PRAGMA user_version` records how far a database is.
Columns named `*_ms` are integer epoch milliseconds. `seq` columns hold the event-stream sequence number
an item was published under, so a client that reconnects can be replayed from here past the memory ring.
"""

MIGRATIONS: list[str] = [
    # 1: the first release.
    """
    CREATE TABLE boots (
        boot_id TEXT PRIMARY KEY,
        started_ms INTEGER NOT NULL,
        first_seq INTEGER NOT NULL,
        ended_ms INTEGER
    );
    CREATE TABLE hubs (
        hub_id TEXT PRIMARY KEY,
        name TEXT NOT NULL,
        kind TEXT NOT NULL,
        address TEXT NOT NULL,
        status TEXT NOT NULL,
        rssi INTEGER,
        last_seen_ms INTEGER,
        firmware TEXT,
        capabilities TEXT NOT NULL DEFAULT '{}',
        staged_program TEXT,
        run_id TEXT,
        run_started_ms INTEGER,
        holder TEXT,
        updated_ms INTEGER NOT NULL
    );
    CREATE TABLE programs (
        program_id INTEGER PRIMARY KEY,
        name TEXT NOT NULL UNIQUE,
        created_ms INTEGER NOT NULL,
        updated_ms INTEGER NOT NULL
    );
    CREATE TABLE program_versions (
        program_id INTEGER NOT NULL REFERENCES programs ON DELETE CASCADE,
        version INTEGER NOT NULL,
        source TEXT NOT NULL,
        sha256 TEXT NOT NULL,
        size INTEGER NOT NULL,
        created_ms INTEGER NOT NULL,
        who TEXT,
        PRIMARY KEY (program_id, version)
    );
    CREATE TABLE runs (
        run_id TEXT PRIMARY KEY,
        hub_id TEXT NOT NULL,
        origin TEXT NOT NULL,
        program_name TEXT,
        program_sha256 TEXT,
        source TEXT,
        slot INTEGER,
        who TEXT,
        boot_id TEXT,
        started_ms INTEGER NOT NULL,
        ended_ms INTEGER,
        outcome TEXT,
        detail TEXT,
        line_count INTEGER NOT NULL DEFAULT 0
    );
    CREATE INDEX runs_by_hub ON runs (hub_id, started_ms);
    CREATE INDEX runs_by_start ON runs (started_ms);
    CREATE INDEX runs_open ON runs (ended_ms) WHERE ended_ms IS NULL;
    CREATE TABLE output_lines (
        id INTEGER PRIMARY KEY,
        run_id TEXT NOT NULL REFERENCES runs ON DELETE CASCADE,
        line_no INTEGER NOT NULL,
        text TEXT NOT NULL,
        hub_ms INTEGER,
        recv_ms INTEGER NOT NULL,
        seq INTEGER,
        UNIQUE (run_id, line_no)
    );
    CREATE INDEX output_by_seq ON output_lines (seq) WHERE seq IS NOT NULL;
    CREATE VIRTUAL TABLE output_fts USING fts5 (text, content='output_lines', content_rowid='id');
    CREATE TRIGGER output_fts_insert AFTER INSERT ON output_lines BEGIN
        INSERT INTO output_fts (rowid, text) VALUES (new.id, new.text);
    END;
    CREATE TRIGGER output_fts_delete AFTER DELETE ON output_lines BEGIN
        INSERT INTO output_fts (output_fts, rowid, text) VALUES ('delete', old.id, old.text);
    END;
    CREATE TABLE telemetry (
        id INTEGER PRIMARY KEY,
        run_id TEXT NOT NULL REFERENCES runs ON DELETE CASCADE,
        name TEXT NOT NULL,
        value REAL NOT NULL,
        hub_ms INTEGER,
        recv_ms INTEGER NOT NULL,
        seq INTEGER
    );
    CREATE INDEX telemetry_by_run ON telemetry (run_id, name);
    CREATE INDEX telemetry_by_seq ON telemetry (seq) WHERE seq IS NOT NULL;
    CREATE TABLE gaps (
        id INTEGER PRIMARY KEY,
        run_id TEXT NOT NULL REFERENCES runs ON DELETE CASCADE,
        reason TEXT NOT NULL,
        since_ms INTEGER NOT NULL,
        until_ms INTEGER
    );
    CREATE TABLE events (
        seq INTEGER PRIMARY KEY,
        type TEXT NOT NULL,
        hub TEXT,
        run TEXT,
        ts INTEGER NOT NULL,
        data TEXT NOT NULL
    );
    CREATE TABLE tokens (
        token_sha256 TEXT PRIMARY KEY,
        label TEXT NOT NULL UNIQUE,
        role TEXT NOT NULL CHECK (role IN ('viewer', 'operator')),
        created_ms INTEGER NOT NULL
    );
    CREATE TABLE audit (
        id INTEGER PRIMARY KEY,
        ts_ms INTEGER NOT NULL,
        who TEXT NOT NULL,
        role TEXT NOT NULL,
        action TEXT NOT NULL,
        status INTEGER NOT NULL
    );
    CREATE INDEX audit_by_time ON audit (ts_ms);
    """,
    # 2: simulator runs. A sim run is a row of `runs` (hub "sim", origin "sim": it is in the history
    # with the hubs' runs) plus what only a sim run has: the job's inputs, its result and its recording.
    """
    CREATE TABLE sim_runs (
        run_id TEXT PRIMARY KEY REFERENCES runs ON DELETE CASCADE,
        world TEXT NOT NULL,
        chassis TEXT,
        seed INTEGER NOT NULL,
        start_mm_deg TEXT,
        speed REAL,
        limit_ms INTEGER NOT NULL,
        wall_limit_s REAL NOT NULL,
        memory_mb INTEGER NOT NULL,
        state TEXT NOT NULL,
        exit TEXT,
        sim_ms INTEGER,
        pose TEXT,
        score TEXT,
        error TEXT,
        recording TEXT
    );
    """,
    # 3: jobs (flash, servo scan / re-ID; sim runs and sweeps may follow): one row per job, kept as history.
    """
    CREATE TABLE jobs (
        job_id TEXT PRIMARY KEY,
        kind TEXT NOT NULL,
        label TEXT NOT NULL,
        batch TEXT,
        who TEXT,
        state TEXT NOT NULL,
        progress REAL,
        message TEXT,
        params TEXT NOT NULL DEFAULT '{}',
        result TEXT,
        steps TEXT NOT NULL DEFAULT '[]',
        created_ms INTEGER NOT NULL,
        started_ms INTEGER,
        ended_ms INTEGER
    );
    CREATE INDEX jobs_by_kind ON jobs (kind, created_ms);
    CREATE INDEX jobs_by_batch ON jobs (batch) WHERE batch IS NOT NULL;
    """,
    # 4: settings the console keeps across restarts (competition mode), one JSON value per key.
    """
    CREATE TABLE settings (
        key TEXT PRIMARY KEY,
        value TEXT NOT NULL,
        who TEXT,
        updated_ms INTEGER NOT NULL
    );
    """,
    # 5: the editor's drafts: a program's unsaved text, kept as it is typed so a page switch, a reload or
    # a closed laptop loses nothing. Keyed by name, not program_id: a new program has a draft before its
    # first version. `base_version` is the version the edit started from (NULL for a new program).
    """
    CREATE TABLE drafts (
        name TEXT PRIMARY KEY,
        source TEXT NOT NULL,
        base_version INTEGER,
        who TEXT,
        updated_ms INTEGER NOT NULL
    );
    """,
]
