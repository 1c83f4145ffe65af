"""Seed sweeps: the seeds a user can write, and one job over many seeds giving the same per-seed results
on the local pool and on a real Dask cluster (a run is a pure function of its job)."""

import socket
import time

import pytest

from openbricks_sim import sweep as sweep_module
from openbricks_sim.job import FINISHED, SimJob, SimResult
from openbricks_sim.sweep import MAX_SEEDS, SeedRow, SweepError, parse_seeds, summarise, sweep

# A curve across the table: where it ends depends on the seed's world (its noise, its blocks).
CURVE = """\
import time
from openbricks.drivers.st3032 import ST3032Motor

left = ST3032Motor(1)
right = ST3032Motor(2, invert=True)
left.run_speed(360)
right.run_speed(330)
time.sleep_ms(3000)
left.brake()
right.brake()
print("done")
"""


@pytest.mark.parametrize(
    ("text", "seeds"),
    [("1-5", [1, 2, 3, 4, 5]), ("3", [3]), ("1,4,9", [1, 4, 9]), ("0-2, 7,1", [0, 1, 2, 7]), (" 8 ", [8])],
)
def test_the_seed_forms_a_user_writes(text, seeds):
    assert parse_seeds(text) == seeds


@pytest.mark.parametrize(
    ("text", "says"),
    [
        ("50-1", "runs backwards; write 1-50"),
        ("", "no seeds given"),
        (" , ", "no seeds given"),
        ("1-x", "'1-x' in --seeds '1-x' is not a seed or a range"),
        ("-3", "is not a seed or a range"),
        ("1.5", "is not a seed or a range"),
        (f"0-{MAX_SEEDS}", f"more than {MAX_SEEDS} seeds"),
        ("1-999999999999", f"more than {MAX_SEEDS} seeds"),
    ],
)
def test_bad_seeds_are_refused_with_what_to_write(text, says):
    with pytest.raises(SweepError, match=says.replace("(", r"\(")):
        parse_seeds(text)


def row(seed, exit=FINISHED, score=None):
    return SeedRow(seed, SimResult(exit=exit, sim_ms=1000, wall_s=0.1, pose={}, output="", score=score))


def test_the_summary_takes_the_worlds_headline_score_and_counts_runs_that_ended_well():
    rows = [row(1, score={"points": 30}), row(2, score={"points": 10}), row(3, "error", {"points": 20})]
    assert summarise(rows) == {
        "seeds": 3,
        "score_key": "points",
        "mean_score": 20.0,
        "median_score": 20,
        "min_score": 10,
        "success_rate": 0.6667,
    }
    no_mission = summarise([row(1, score={"zone": "red"})])
    assert no_mission["mean_score"] is None and no_mission["success_rate"] == 1.0


def comparable(rows):
    """What must not depend on where a seed ran (wall time does, so it is left out)."""
    return {r.seed: {key: value for key, value in r.summary().items() if key != "wall_s"} for r in rows}


@pytest.mark.e2e
def test_twenty_seeds_on_a_dask_cluster_and_on_the_local_pool_give_the_same_results(tmp_path):
    from distributed import LocalCluster

    program = tmp_path / "mission.py"
    program.write_text(CURVE)
    job = SimJob(str(program), world="wro", limit_ms=5000)
    seeds = list(range(1, 21))
    local = list(sweep(job, seeds, workers=2))
    with LocalCluster(
        n_workers=2, threads_per_worker=1, processes=True, host="127.0.0.1", dashboard_address=None
    ) as cluster:
        on_dask = list(sweep(job, seeds, dask=cluster.scheduler_address))
    assert sorted(r.seed for r in local) == seeds == sorted(r.seed for r in on_dask)
    assert all(r.result.exit == FINISHED for r in local), [r.result.error for r in local]
    assert comparable(local) == comparable(on_dask)
    assert len({r.result.pose["heading_deg"] for r in local}) > 1, "the seeds should not all end alike"
    assert {r.result.job["program"] for r in on_dask} == {str(program)}


def test_an_unreachable_dask_scheduler_is_a_clear_error_within_the_timeout(tmp_path, monkeypatch):
    monkeypatch.setattr(sweep_module, "DASK_CONNECT_TIMEOUT_S", 2.0)
    with socket.socket() as free:
        free.bind(("127.0.0.1", 0))
        port = free.getsockname()[1]  # closed again: nothing listens there
    program = tmp_path / "mission.py"
    program.write_text("print('hi')\n")
    started = time.monotonic()
    with pytest.raises(
        SweepError, match=f"cannot reach the Dask scheduler at tcp://127.0.0.1:{port} within 2 s"
    ):
        list(sweep(SimJob(str(program)), [1, 2], dask=f"tcp://127.0.0.1:{port}"))
    assert time.monotonic() - started < 30


def test_something_else_listening_at_the_address_is_named_as_not_a_scheduler(tmp_path):
    """A web server on the wrong port: Dask's handshake would read its reply as a message length."""
    import threading

    server = socket.create_server(("127.0.0.1", 0))
    port = server.getsockname()[1]

    def answer():
        with server:
            conn, _ = server.accept()
            with conn:
                conn.sendall(b"HTTP/1.1 400 Bad Request\r\nContent-Length: 0\r\n\r\n" * 4)
                time.sleep(1.0)

    threading.Thread(target=answer, daemon=True).start()
    program = tmp_path / "mission.py"
    program.write_text("print('hi')\n")
    with pytest.raises(SweepError, match="something other than a Dask scheduler answered"):
        list(sweep(SimJob(str(program)), [1], dask=f"tcp://127.0.0.1:{port}"))
