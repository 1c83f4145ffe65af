"""The console's database: WAL, migrations, the run history's search and full-text index, exports."""

import io
import json
import sqlite3
import zipfile

import pytest

from openbricks_server.daemon.hub_events import HubState
from openbricks_server.daemon.store import RunQuery, Store, StoreError
from openbricks_server.daemon.store.migrations import MIGRATIONS


@pytest.fixture
def store(tmp_path):
    opened = Store(tmp_path / "console.sqlite3")
    yield opened
    opened.close()


def _run(store, run_id, hub="hub-a", started=1_000, lines=(), **kw):
    store.runs.insert(run_id, hub, kw.pop("origin", "daemon"), started, **kw)
    store.runs.append([(run_id, i + 1, text, None, started + i, None) for i, text in enumerate(lines)], [])


def test_a_new_database_is_in_wal_mode_at_the_newest_schema(store):
    assert store.db.query_one("PRAGMA journal_mode")[0] == "wal"
    assert store.db.schema_version == len(MIGRATIONS)
    assert store.db.query_one("PRAGMA integrity_check")[0] == "ok"


def test_reopening_keeps_the_data_and_applies_nothing_twice(tmp_path):
    first = Store(tmp_path / "db.sqlite3")
    first.programs.save("square.py", "print(1)\n", "local")
    first.close()
    again = Store(tmp_path / "db.sqlite3")
    assert again.programs.version("square.py", None)["source"] == "print(1)\n"
    assert again.db.schema_version == len(MIGRATIONS)


def test_an_older_database_is_migrated_forward(tmp_path, monkeypatch):
    path = tmp_path / "db.sqlite3"
    conn = sqlite3.connect(path)
    conn.execute("CREATE TABLE kept (x)")
    conn.execute("PRAGMA user_version=0")
    conn.close()
    migrated = Store(path)
    assert migrated.db.schema_version == len(MIGRATIONS)
    assert migrated.db.query_one("SELECT count(*) FROM runs")[0] == 0


def test_a_database_from_a_newer_release_is_refused_with_what_to_do(tmp_path):
    path = tmp_path / "db.sqlite3"
    conn = sqlite3.connect(path)
    conn.execute(f"PRAGMA user_version={len(MIGRATIONS) + 5}")
    conn.close()
    with pytest.raises(StoreError, match="newer openbricks.*--data-dir"):
        Store(path)


def test_a_file_that_is_not_a_database_is_refused(tmp_path):
    path = tmp_path / "db.sqlite3"
    path.write_bytes(b"this is not sqlite" * 100)
    with pytest.raises(StoreError, match="move it aside"):
        Store(path)


def test_program_versions_are_kept_and_an_unchanged_save_adds_none(store):
    v1, new1 = store.programs.save("square.py", "print(1)\n", "alice")
    v1_again, new_again = store.programs.save("square.py", "print(1)\n", "alice")
    v2, new2 = store.programs.save("square.py", "print(2)\n", "bob")
    assert (new1, new_again, new2) == (True, False, True)
    assert (v1["version"], v1_again["version"], v2["version"]) == (1, 1, 2)
    assert [v["version"] for v in store.programs.versions("square.py")] == [2, 1]
    assert store.programs.version("square.py", 1)["source"] == "print(1)\n"
    assert store.programs.version("square.py", None)["who"] == "bob"
    assert [p["name"] for p in store.programs.list()] == ["square.py"]
    assert store.programs.delete("square.py") and store.programs.version("square.py", None) is None


def test_search_by_hub_text_date_outcome_and_origin(store):
    store.hubs.upsert(HubState("hub-a", "RobotA", "virtual", "v1"))
    _run(store, "01A0000000000000000000000A", "hub-a", 1_000, ["left motor stalled", "done"])
    _run(store, "01A0000000000000000000000B", "hub-b", 2_000, ["all good"], origin="button")
    _run(store, "01A0000000000000000000000C", "hub-a", 3_000, ["stalled again"], program_name="line.py")
    store.runs.end("01A0000000000000000000000A", "error", "OSError", 1_500)

    def ids(**kw):
        return [r["run_id"][-1] for r in store.runs.search(RunQuery(**kw))]

    assert ids() == ["C", "B", "A"]  # newest first
    assert ids(hub="RobotA") == ["C", "A"]  # by name
    assert ids(hub="hub-b") == ["B"]  # by id
    assert ids(text="stalled") == ["C", "A"]  # full text
    assert ids(text="motor stalled") == ["A"]  # every word
    assert ids(text="line.py") == ["C"]  # program name
    assert ids(since_ms=1_500, until_ms=3_000) == ["B"]
    assert ids(outcome="error") == ["A"]
    assert ids(outcome="running") == ["C", "B"]
    assert ids(origin="button") == ["B"]
    assert ids(limit=1) == ["C"] and ids(before="01A0000000000000000000000C", limit=1) == ["B"]


@pytest.mark.parametrize(
    "text", ['"', "AND OR NOT", "*", "a:b", "(", "NEAR(", "-x", "''", "%_\\", "\u00b9/\x00"]
)
def test_search_text_is_never_query_syntax(store, text):
    _run(store, "01A0000000000000000000000A", lines=["plain"])
    assert store.runs.search(RunQuery(text=text)) == []


def test_a_line_number_already_stored_is_not_duplicated(store):
    _run(store, "01A0000000000000000000000A", lines=["one", "two"])
    store.runs.append([("01A0000000000000000000000A", 2, "two again", None, 5, None)], [])
    store.runs.append([("01A0000000000000000000000A", 3, "three", None, 6, None)], [])
    lines = store.runs.lines("01A0000000000000000000000A")
    assert [(ln["line_no"], ln["text"]) for ln in lines] == [(1, "one"), (2, "two"), (3, "three")]
    assert store.runs.get("01A0000000000000000000000A")["line_count"] == 3


def test_runs_left_open_by_a_crash_are_marked_interrupted_at_their_last_line(store):
    _run(store, "01A0000000000000000000000A", started=1_000, lines=["a", "b"], boot_id="old")
    _run(store, "01A0000000000000000000000B", started=2_000, boot_id="current")
    assert store.runs.mark_interrupted("current", "daemon stopped") == 1
    run = store.runs.get("01A0000000000000000000000A")
    assert (run["outcome"], run["ended_ms"], run["detail"]) == ("interrupted", 1_001, "daemon stopped")
    assert store.runs.get("01A0000000000000000000000B")["outcome"] is None


def test_a_run_log_slot_matches_the_live_run_within_two_seconds(store):
    _run(store, "01A0000000000000000000000A", started=10_000, slot=3)
    assert store.runs.find_by_slot("hub-a", 3, 11_500)["run_id"] == "01A0000000000000000000000A"
    assert store.runs.find_by_slot("hub-a", 3, 13_000) is None
    assert store.runs.find_by_slot("hub-a", 4, 10_000) is None


def test_tokens_are_stored_hashed(store):
    token = store.tokens.mint("viewer", "mentor")
    assert store.tokens.lookup(token) == ("mentor", "viewer")
    assert store.tokens.lookup(token + "x") is None
    dump = "\n".join(store.db._conn.iterdump())
    assert token not in dump
    assert store.tokens.revoke("mentor") and store.tokens.lookup(token) is None


def test_export_as_text_json_and_zip(store):
    from openbricks_server.daemon.store.export import run_json, run_text, runs_zip

    _run(store, "01A0000000000000000000000A", lines=["hello", "world"], program_name="hi.py", source="x=1\n")
    store.runs.append([], [("01A0000000000000000000000A", "speed", 12.5, 7, 8, None)])
    store.runs.add_gap("01A0000000000000000000000A", "link dropped", 1_000, 1_200)
    store.runs.end("01A0000000000000000000000A", "finished", None, 2_000)
    run = store.runs.get("01A0000000000000000000000A")
    text = run_text(store.runs, run)
    assert text.endswith("\n\nhello\nworld\n") and "program: hi.py" in text and "gap: link dropped" in text
    exported = run_json(store.runs, run)
    assert exported["source"] == "x=1\n" and [ln["text"] for ln in exported["lines"]] == ["hello", "world"]
    assert exported["telemetry"][0]["value"] == 12.5 and exported["gaps"][0]["reason"] == "link dropped"
    archive = zipfile.ZipFile(io.BytesIO(runs_zip(store.runs, [run])))
    assert sorted(archive.namelist()) == ["01A0000000000000000000000A.json", "01A0000000000000000000000A.txt"]
    assert json.loads(archive.read("01A0000000000000000000000A.json"))["outcome"] == "finished"


def test_drafts_are_one_per_name_and_survive_a_reopen(tmp_path):
    first = Store(tmp_path / "db.sqlite3")
    first.drafts.put("square.py", "a", None, "local")
    first.drafts.put("square.py", "ab", 2, "local")
    first.close()
    again = Store(tmp_path / "db.sqlite3")
    kept = again.drafts.get("square.py")
    assert (kept["source"], kept["base_version"]) == ("ab", 2)
    again.drafts.put("other.py", "c", None, None)
    again.drafts.rename("square.py", "other.py")  # the renamed program's draft wins
    assert [d["name"] for d in again.drafts.list()] == ["other.py"]
    assert again.drafts.get("other.py")["source"] == "ab"
    assert again.drafts.delete("other.py") and not again.drafts.delete("other.py")
    again.close()
