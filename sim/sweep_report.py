"""`openbricks sim sweep`'s output: a table (or JSON) of the seeds, a summary, and a CSV file.

Rows arrive in the order the seeds finish; the table and the files list them by seed, so two sweeps
of the same job read the same whatever ran where. A person at a terminal sees each seed as it ends.
"""

from __future__ import annotations

import csv
import json
import os
import signal
import sys

from .sweep import SeedRow, SweepError, summarise, sweep

EXIT_OK = 0
EXIT_INTERRUPTED = 130
CSV_COLUMNS = (
    "seed",
    "exit",
    "score",
    "sim_s",
    "x_mm",
    "y_mm",
    "heading_deg",
    "wall_s",
    "error",
    "score_json",
)


def run_sweep(job, seeds, source, args) -> int:
    """Run the sweep the parsed `args` describe, report it; the command's exit status."""
    if args.csv:
        check_csv_path(args.csv)
    rows: list[SeedRow] = []
    progress = sys.stderr.isatty() and not args.json
    # A SIGTERM or SIGHUP ends the sweep as Ctrl-C does: the seeds' children run in sessions of
    # their own, so only the sweep can stop them, and it must get to do so.
    previous = {signum: signal.signal(signum, _interrupt) for signum in (signal.SIGTERM, signal.SIGHUP)}
    try:
        for row in sweep(job, seeds, workers=args.workers, dask=args.dask, source=source):
            rows.append(row)
            if progress:
                print(f"  [{len(rows)}/{len(seeds)}] seed {row.seed}: {row.result.exit}", file=sys.stderr)
    except KeyboardInterrupt:
        print(f"sweep interrupted after {len(rows)} of {len(seeds)} seeds", file=sys.stderr)
        return EXIT_INTERRUPTED
    finally:
        for signum, handler in previous.items():
            signal.signal(signum, handler)
    rows.sort(key=lambda row: row.seed)
    summary = summarise(rows)
    if args.json:
        print(json.dumps({"rows": [row.summary() for row in rows], "summary": summary}))
    else:
        print(table(rows, summary))
    if args.csv:
        try:
            write_csv(args.csv, rows)
        except OSError as exc:
            raise SweepError(f"cannot write the CSV file {args.csv}: {exc.strerror or exc}") from None
    return EXIT_OK


def check_csv_path(path: str) -> None:
    """Refuse a CSV path that cannot be written before any seed runs, not after all of them."""
    folder = os.path.dirname(os.path.abspath(path))
    if os.path.isdir(path):
        raise SweepError(
            f"--csv {path} is a folder: give a file name, e.g. {os.path.join(path, 'sweep.csv')}"
        )
    if not os.path.isdir(folder):
        raise SweepError(f"--csv {path}: the folder {folder} does not exist")
    if not os.access(folder, os.W_OK):
        raise SweepError(f"--csv {path}: the folder {folder} is not writable")


def _interrupt(_signum, _frame):
    raise KeyboardInterrupt


def table(rows: list[SeedRow], summary: dict) -> str:
    """The seeds as aligned columns, then one line of summary."""
    key = summary["score_key"] or "score"
    lines = [f"{'seed':>6}  {'exit':<12} {key:>12} {'sim s':>8} {'x mm':>9} {'y mm':>9} {'heading':>8}"]
    for row in rows:
        pose = row.result.pose or {}
        where = " ".join(
            _cell(pose.get(name), width, 1) for name, width in (("x_mm", 9), ("y_mm", 9), ("heading_deg", 8))
        )
        sim_s = row.result.sim_ms / 1000
        lines.append(f"{row.seed:>6}  {row.result.exit:<12} {_cell(row.headline, 12)} {sim_s:>8.3f} {where}")
    scores = (
        f"score ({key}) mean {summary['mean_score']:g}, median {summary['median_score']:g}, "
        f"min {summary['min_score']:g}"
        if summary["mean_score"] is not None
        else "no score (this world has no mission to score)"
    )
    lines.append(f"{summary['seeds']} seeds: {scores}; {summary['success_rate']:.0%} ran to the end")
    return "\n".join(lines)


def _cell(value, width, decimals=None) -> str:
    if value is None:
        return f"{'-':>{width}}"
    if decimals is None:
        return f"{value:>{width}g}"
    return f"{value:>{width}.{decimals}f}"


def write_csv(path: str, rows: list[SeedRow]) -> None:
    """One line per seed; the world's whole score dict as JSON in the last column."""
    with open(path, "w", newline="", encoding="utf-8") as f:
        write_csv_to(f, rows)


def write_csv_to(stream, rows: list[SeedRow]) -> None:
    """write_csv's lines into an open text stream (the console answers with them)."""
    writer = csv.writer(stream)
    writer.writerow(CSV_COLUMNS)
    for row in rows:
        result, pose = row.result, row.result.pose or {}
        error = (result.error or "").strip().splitlines()
        writer.writerow(
            [
                row.seed,
                result.exit,
                row.headline,
                result.sim_ms / 1000,
                pose.get("x_mm"),
                pose.get("y_mm"),
                pose.get("heading_deg"),
                result.wall_s,
                error[-1] if error else "",
                json.dumps(result.score),
            ]
        )
