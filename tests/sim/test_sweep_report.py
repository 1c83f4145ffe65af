"""`openbricks sim sweep` as a user sees it: the table, --json rows, the CSV file, and bad input refused
with one line before any seed runs."""

import csv
import json
import os
import signal
import socket
import subprocess
import sys
import time

import pytest

from openbricks_sim import cli
from openbricks_sim import sweep as sweep_module

POSE_KEYS = {"x_mm", "y_mm", "heading_deg"}
SHORT_DRIVE = """\
import time
from openbricks.drivers.st3032 import ST3032Motor

left = ST3032Motor(1)
right = ST3032Motor(2, invert=True)
left.run_speed(360)
right.run_speed(360)
time.sleep_ms(800)
print("done")
"""


@pytest.fixture
def program(tmp_path):
    path = tmp_path / "mission.py"
    path.write_text(SHORT_DRIVE)
    return path


def sweep(*args):
    return cli.main(["sweep", *map(str, args)])


def test_the_table_lists_each_seed_in_order_with_a_summary(program, capsys):
    assert sweep(program, "--world", "line_track", "--seeds", "3,1-2", "--workers", "2") == cli.EXIT_OK
    lines = capsys.readouterr().out.splitlines()
    assert lines[0].split() == ["seed", "exit", "progress_pct", "sim", "s", "x", "mm", "y", "mm", "heading"]
    assert [line.split()[:2] for line in lines[1:4]] == [[str(seed), "finished"] for seed in (1, 2, 3)]
    assert lines[4].startswith("3 seeds: score (progress_pct) mean ") and lines[4].endswith(
        "100% ran to the end"
    )


def test_json_rows_carry_sim_runs_keys_and_the_csv_a_row_per_seed(program, tmp_path, capsys):
    table = tmp_path / "sweep.csv"
    status = sweep(
        program, "--world", "line_track", "--seeds", "1-2", "--json", "--csv", table, "--duration", "2"
    )
    assert status == cli.EXIT_OK
    report = json.loads(capsys.readouterr().out)
    assert [row["seed"] for row in report["rows"]] == [1, 2]
    for row in report["rows"]:
        assert {"seed", "score", "exit", "sim_s", "pose"} <= set(row)
        assert row["exit"] == "finished" and row["sim_s"] > 0.8 and set(row["pose"]) == POSE_KEYS
        assert "progress_pct" in row["score"]
    summary = report["summary"]
    assert summary["seeds"] == 2 and summary["success_rate"] == 1.0 and summary["score_key"] == "progress_pct"
    assert (
        summary["min_score"]
        <= summary["median_score"]
        <= max(r["score"]["progress_pct"] for r in report["rows"])
    )
    with open(table, newline="") as f:
        rows = list(csv.DictReader(f))
    assert [row["seed"] for row in rows] == ["1", "2"]
    assert rows[0]["exit"] == "finished" and float(rows[0]["x_mm"]) == report["rows"][0]["pose"]["x_mm"]
    assert json.loads(rows[1]["score_json"]) == report["rows"][1]["score"]


@pytest.mark.parametrize(
    ("args", "says"),
    [
        (["--world", "moon", "--seeds", "1-3"], "unknown world 'moon'"),
        (["--seeds", "9-2"], "the range 9-2 runs backwards; write 2-9"),
        (["--seeds", "1", "--dask", "scheduler"], "give the scheduler's address as tcp://HOST:PORT"),
        (["--seeds", "1-50000"], "more than 10000 seeds"),
        (["--seeds", "one"], "'one' in --seeds 'one' is not a seed or a range"),
        (
            ["--seeds", "1-3", "--workers", "2", "--dask", "tcp://127.0.0.1:1"],
            "--workers is for the local pool",
        ),
        (
            ["--seeds", "1", "--csv", "/nonexistent-folder/out.csv"],
            "the folder /nonexistent-folder does not exist",
        ),
    ],
)
def test_bad_input_is_one_line_before_any_seed_runs(program, capsys, args, says):
    started = time.monotonic()
    assert sweep(program, *args) == cli.EXIT_FAILED
    err = capsys.readouterr().err
    assert err.startswith("openbricks sim sweep: error: ") and says in err and "Traceback" not in err
    assert time.monotonic() - started < 5, "refused before any seed ran"


def test_an_unknown_chassis_or_a_missing_program_is_refused(program, tmp_path, capsys):
    with pytest.raises(SystemExit) as exited:
        sweep(program, "--seeds", "1", "--chassis", "tank")
    assert exited.value.code == 2 and "invalid choice: 'tank'" in capsys.readouterr().err
    assert sweep(tmp_path / "missing.py", "--seeds", "1") == cli.EXIT_FAILED
    assert "missing.py: no such program file" in capsys.readouterr().err


def test_an_unreachable_dask_scheduler_is_named_with_what_to_check(program, capsys, monkeypatch):
    monkeypatch.setattr(sweep_module, "DASK_CONNECT_TIMEOUT_S", 2.0)
    with socket.socket() as free:
        free.bind(("127.0.0.1", 0))
        port = free.getsockname()[1]
    assert sweep(program, "--seeds", "1-3", "--dask", f"tcp://127.0.0.1:{port}") == cli.EXIT_FAILED
    err = capsys.readouterr().err
    assert f"cannot reach the Dask scheduler at tcp://127.0.0.1:{port} within 2 s" in err
    assert "is `dask scheduler` running there" in err


def _children(pid):
    """The processes whose parent is `pid` now."""
    found = []
    for entry in filter(str.isdigit, os.listdir("/proc")):
        try:
            with open(f"/proc/{entry}/stat", encoding="ascii") as f:
                fields = f.read().rsplit(")", 1)[1].split()
        except OSError:
            continue
        if int(fields[1]) == pid and fields[0] != "Z":
            found.append(int(entry))
    return found


def _alive(pid):
    try:
        with open(f"/proc/{pid}/stat", encoding="ascii") as f:
            return f.read().rsplit(")", 1)[1].split()[0] != "Z"
    except OSError:
        return False


@pytest.mark.e2e
@pytest.mark.parametrize("signum", [signal.SIGINT, signal.SIGTERM])
def test_ctrl_c_or_sigterm_ends_a_sweep_and_stops_every_running_seed(tmp_path, signum):
    program = tmp_path / "forever_sweep_probe.py"
    program.write_text("while True:\n    pass\n")  # no simulated time passes: it runs until stopped
    sweep_cli = subprocess.Popen(
        [sys.executable, "-m", "openbricks_server.cli", "sim", "sweep", str(program), "--seeds", "1-4"]
        + ["--workers", "2", "--duration", "3600", "--wall-limit", "600"],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )

    def seeds_running():
        # The CLI's child is the sweep's fork server; each seed is a child of that.
        return [seed for server in _children(sweep_cli.pid) for seed in _children(server)]

    seen = []
    try:
        deadline = time.monotonic() + 60
        while len(seeds_running()) < 2 and time.monotonic() < deadline:
            time.sleep(0.2)
        seen = seeds_running()
        assert len(seen) == 2, f"two seeds should be running: {seen}"
        sweep_cli.send_signal(signum)
        _, err = sweep_cli.communicate(timeout=60)
        assert sweep_cli.returncode == 130, err
        assert "sweep interrupted after 0 of 4 seeds" in err and "Traceback" not in err, err
        assert [pid for pid in seen if _alive(pid)] == [], err
    finally:
        sweep_cli.kill()
        for pid in seen:  # a failed test leaves no runs behind
            if _alive(pid):
                os.kill(pid, signal.SIGKILL)
