"""A run as a file a user can keep or send: plain text (what the terminal showed), JSON (everything), and
many runs as one zip of both."""

from __future__ import annotations

import io
import json
import zipfile
from datetime import UTC, datetime

from openbricks_server.daemon.store.runs import Runs


def _stamp(ms: int | None) -> str:
    if ms is None:
        return "-"
    return datetime.fromtimestamp(ms / 1000, tz=UTC).isoformat(timespec="milliseconds")


def run_json(runs: Runs, run: dict) -> dict:
    return {
        **run,
        "lines": runs.lines(run["run_id"]),
        "telemetry": runs.telemetry(run["run_id"]),
        "gaps": runs.gaps(run["run_id"]),
    }


def run_text(runs: Runs, run: dict) -> str:
    head = [
        f"run {run['run_id']} on hub {run['hub_id']} ({run['origin']})",
        f"program: {run['program_name'] or '-'}  sha256: {run['program_sha256'] or '-'}",
        f"started: {_stamp(run['started_ms'])}  ended: {_stamp(run['ended_ms'])}",
        f"outcome: {run['outcome'] or 'running'}" + (f" ({run['detail']})" if run["detail"] else ""),
    ]
    for gap in runs.gaps(run["run_id"]):
        head.append(f"gap: {gap['reason']} from {_stamp(gap['since_ms'])} to {_stamp(gap['until_ms'])}")
    body = [line["text"] for line in runs.lines(run["run_id"])]
    return "\n".join(head) + "\n\n" + "".join(text + "\n" for text in body)


def runs_zip(runs: Runs, selected: list[dict]) -> bytes:
    buffer = io.BytesIO()
    with zipfile.ZipFile(buffer, "w", zipfile.ZIP_DEFLATED) as archive:
        for run in selected:
            archive.writestr(f"{run['run_id']}.txt", run_text(runs, run))
            archive.writestr(f"{run['run_id']}.json", json.dumps(run_json(runs, run), indent=1))
    return buffer.getvalue()
