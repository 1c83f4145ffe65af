"""A SimJob is what a daemon stores and a child process runs: it must survive JSON unchanged, and a
bad one must be refused with the field named before any simulator starts."""

import json

import pytest

from openbricks_sim.job import JobError, SimJob


def test_a_job_survives_json_unchanged():
    job = SimJob("mission.py", world="wro", chassis="jgb37", seed=7, start_mm_deg=(1, 2.5, -90), speed=2.0)
    assert SimJob.from_dict(json.loads(job.to_json())) == job
    assert job.to_dict()["start_mm_deg"] == [1.0, 2.5, -90.0]
    assert job.with_seed(8).seed == 8 and job.seed == 7


@pytest.mark.parametrize(
    ("fields", "named"),
    [
        ({"seed": -1}, "seed"),
        ({"seed": 1.5}, "seed"),
        ({"chassis": "tank"}, "chassis"),
        ({"speed": 0}, "speed"),
        ({"limit_ms": 0}, "limit_ms"),
        ({"start_mm_deg": [0, 0]}, "start_mm_deg"),
        ({"wall_limit_s": -2}, "wall_limit_s"),
        ({"range_finder": "sonar"}, "range_finder"),
        ({"bare_0x29": "bmp280"}, "bare_0x29"),
    ],
)
def test_a_bad_field_is_refused_by_name(fields, named):
    with pytest.raises(JobError, match=f"field {named}: give "):
        SimJob.from_dict({"program": "mission.py", **fields})


def test_unknown_fields_and_a_missing_program_are_refused():
    with pytest.raises(JobError, match="unknown sim job field.*colour"):
        SimJob.from_dict({"program": "mission.py", "colour": "red"})
    with pytest.raises(JobError, match="needs its program"):
        SimJob.from_dict({"world": "wro"})


def test_limits_default_from_the_simulated_time_and_a_watched_run_has_none():
    job = SimJob("mission.py", limit_ms=30_000)
    assert job.wall_limit() == 30 and job.cpu_limit() == 35
    assert job.wall_limit(watched=True) is None and job.cpu_limit(watched=True) is None
    assert SimJob("mission.py", limit_ms=30_000, speed=0.5).wall_limit() == 120
    assert SimJob("mission.py", wall_limit_s=0).wall_limit() is None  # 0: no limit
