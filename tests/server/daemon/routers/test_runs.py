"""The run history over the API: search, one run, its output in pages, telemetry and exports."""

import io
import time
import zipfile

from openbricks_server.daemon.hub_events import OutputLine, RunStart, TelemetrySample


def _record(daemon, hub="hub-a", lines=("hello", "world"), outcome="finished"):
    events = daemon.ctx.hub_events
    now = int(time.time() * 1000)
    run = daemon.call(events.run_started, RunStart(hub, "daemon", now, "hi.py", "print('hi')\n", 2, "local"))
    daemon.call(events.run_output, run, [OutputLine(i + 1, t, now + i, now + i) for i, t in enumerate(lines)])
    daemon.call(events.run_telemetry, run, [TelemetrySample("speed", 1.5, now, now)])
    if outcome:
        daemon.call(events.run_ended, run, outcome, None, now + 100)
    return run


def test_a_run_reads_back_with_source_output_and_telemetry(daemon, operator):
    run = _record(daemon)
    detail = operator.get(f"/api/runs/{run}").json()
    assert (
        detail["source"] == "print('hi')\n" and detail["outcome"] == "finished" and detail["line_count"] == 2
    )
    assert detail["program_sha256"] and detail["slot"] == 2 and detail["who"] == "local"
    page = operator.get(f"/api/runs/{run}/output", params={"limit": 1}).json()
    assert [ln["text"] for ln in page["lines"]] == ["hello"] and page["more"]
    rest = operator.get(f"/api/runs/{run}/output", params={"after": page["next_after"]}).json()
    assert [ln["text"] for ln in rest["lines"]] == ["world"] and not rest["more"]
    assert operator.get(f"/api/runs/{run}/telemetry").json()[0]["value"] == 1.5


def test_search_and_export(daemon, operator):
    first = _record(daemon, "hub-a", ["motor stalled"], "error")
    second = _record(daemon, "hub-b", ["all fine"])
    assert [r["run_id"] for r in operator.get("/api/runs").json()] == [second, first]
    assert [r["run_id"] for r in operator.get("/api/runs", params={"q": "stalled"}).json()] == [first]
    assert [r["run_id"] for r in operator.get("/api/runs", params={"outcome": "error"}).json()] == [first]
    assert [r["run_id"] for r in operator.get("/api/runs", params={"hub": "hub-b"}).json()] == [second]
    assert operator.get("/api/runs", params={"since": "2999-01-01T00:00:00"}).json() == []
    text = operator.get(f"/api/runs/{first}/export", params={"format": "text"})
    assert text.headers["content-type"].startswith("text/plain") and text.text.endswith("motor stalled\n")
    exported = operator.get(f"/api/runs/{first}/export").json()
    assert exported["lines"][0]["text"] == "motor stalled"
    archive = zipfile.ZipFile(io.BytesIO(operator.get("/api/runs/export").content))
    assert len(archive.namelist()) == 4


def test_output_is_readable_while_the_run_is_on(daemon, operator):
    run = _record(daemon, outcome=None)
    assert operator.get(f"/api/runs/{run}").json()["outcome"] is None
    assert len(operator.get(f"/api/runs/{run}/output").json()["lines"]) == 2


def test_unknown_and_malformed_run_ids(operator):
    missing = operator.get("/api/runs/01ARZ3NDEKTSV4RRFFQ69G5FAV")
    assert missing.status_code == 404 and missing.json()["error"] == "not_found"
    bad = operator.get("/api/runs/../../etc")
    assert bad.status_code in (404, 422)
    malformed = operator.get("/api/runs/not-a-run-id/output")
    assert malformed.status_code == 422 and malformed.json()["error"] == "bad_run_id"
    bad_date = operator.get("/api/runs", params={"since": "yesterday"})
    assert bad_date.status_code == 422 and bad_date.json()["message"].startswith("since")
