"""The world file's checks: a good file reads into the frame a team measures in, and each problem
of a bad one is one line naming the file, the line and the key."""

import pytest

from openbricks_sim.job import UnknownWorldError, world_file
from openbricks_sim.world_file import WorldFileError, load, mat_size_argument, open_world

from .season_table import WORLD_TOML, write_table


def test_a_good_file_reads_its_start_props_slots_zones_and_rules(tmp_path):
    spec = load(write_table(tmp_path))
    assert spec.name == "season table"
    assert spec.size_mm == (2362.0, 1143.0)
    assert spec.start == (250.0, 571.0, 0.0)
    assert spec.start_mm_deg == (250.0 - 1181.0, 571.0 - 571.5, -0.0)
    assert spec.walls == (70.0, 20.0)
    assert [(p.name, p.count, p.slots) for p in spec.props] == [
        ("red_block", 2, "north"),
        ("blue", 1, "north"),
        ("pusher_target", 1, None),
    ]
    assert len(spec.slots["north"].positions) == 5
    assert [z.name for z in spec.zones] == ["parking", "green_goal"]
    assert spec.zones[1].contains(1000, 900) and not spec.zones[1].contains(999, 950)
    assert [(r.zone, r.points, r.robot) for r in spec.rules] == [
        ("green_goal", 25, False),
        ("parking", 5, True),
    ]
    assert spec.time_limit_s == 150
    assert world_file(str(tmp_path / "table.toml")) == tmp_path / "table.toml"


def test_every_problem_is_one_line_with_the_file_line_and_key(tmp_path):
    bad = (
        WORLD_TOML.replace('mat = "mat.png"', 'mat = "missing.png"')
        .replace("size_mm = [2362, 1143]", "size_mm = [2362, -5]\ncolour = 'blue'")
        .replace("[1800, 850]", "[1800, 2850]")
        .replace("points = 5", "points = 5\nbonus = 3")
    )
    path = tmp_path / "table.toml"
    path.write_text(bad)
    with pytest.raises(WorldFileError) as caught:
        load(path)
    problems = caught.value.problems
    lines = bad.splitlines()

    def line_of(text):
        return next(i for i, line in enumerate(lines, start=1) if text in line)

    assert (
        f"{path}:{line_of('missing.png')}: mat: image 'missing.png' not found"
        in problems[[i for i, p in enumerate(problems) if ": mat:" in p][0]]
    )
    assert any(
        p.startswith(f"{path}:{line_of('size_mm = [2362, -5]')}: size_mm: must be positive") for p in problems
    )
    assert any(p.startswith(f"{path}:{line_of('colour =')}: colour: unknown key") for p in problems)
    assert any(p.startswith(f"{path}:{line_of('bonus')}: scoring[2].bonus: unknown key") for p in problems)
    assert isinstance(caught.value, UnknownWorldError)  # every front end prints it without a traceback


def test_a_slot_outside_the_mat_and_a_rule_naming_no_zone_are_told(tmp_path):
    path = write_table(
        tmp_path,
        WORLD_TOML.replace("[2100, 850]]", "[2400, 850]]").replace('zone = "parking"', 'zone = "garage"'),
    )
    with pytest.raises(WorldFileError) as caught:
        load(path)
    text = str(caught.value)
    assert "slots.north.positions[5]: (2400, 850) puts a slot outside the mat" in text
    assert "scoring[2].zone: no zone 'garage' (zones: green_goal, parking)" in text
    assert len(caught.value.problems) == 2


def test_not_toml_missing_keys_and_a_bare_image_without_its_size(tmp_path):
    path = tmp_path / "t.toml"
    path.write_text('mat = "x.png"\nsize_mm = = 3\n')
    with pytest.raises(WorldFileError, match=r"t.toml:2: not valid TOML"):
        load(path)
    path.write_text("")
    with pytest.raises(WorldFileError) as caught:
        load(path)
    assert [p.split(": ")[1] for p in caught.value.problems] == ["size_mm", "mat", "start"]
    with pytest.raises(WorldFileError, match="--mat-size"):
        open_world(str(tmp_path / "mat.png"))
    with pytest.raises(ValueError, match="WIDTHxHEIGHT"):
        mat_size_argument("2362 by 1143")
    assert mat_size_argument("2362x1143") == (2362.0, 1143.0)


def test_the_manuals_example_world_file_reads_as_written(tmp_path):
    from pathlib import Path

    page = (Path(__file__).resolve().parents[2] / "docs" / "season-table.md").read_text()
    example = page.split("```toml\n", 1)[1].split("```", 1)[0]
    write_table(tmp_path)  # its mat.png
    path = tmp_path / "season.toml"
    path.write_text(example)
    spec = load(path)
    assert spec.name == "season 2026" and spec.obstacles[0].name == "tower"
    assert [r.points for r in spec.rules] == [25, 5, -10]
    from openbricks_sim.worlds import resolve

    assert resolve(str(path)).build(3).compile().nbody == 4  # the world body and the three props


def test_a_mat_that_is_not_the_image_its_name_says_is_told_by_the_line(tmp_path):
    path = write_table(tmp_path)
    (tmp_path / "mat.png").write_bytes(b"GIF89a not a png")
    with pytest.raises(WorldFileError) as caught:
        load(path)
    assert caught.value.problems == [
        f"{path}:3: mat: 'mat.png' is not a PNG file (its first bytes say otherwise)"
    ]


def test_a_world_files_time_limit_is_a_runs_duration_unless_duration_is_given(tmp_path):
    from openbricks_sim.cli import build_parser
    from openbricks_sim.job import job_from_args

    world = str(write_table(tmp_path))
    parser = build_parser()
    assert job_from_args(parser.parse_args(["run", "m.py", "--world", world]), "m.py").limit_ms == 150_000
    given = parser.parse_args(["sweep", "m.py", "--world", world, "--duration", "2", "--seeds", "1-2"])
    assert job_from_args(given, "m.py").limit_ms == 2_000
    assert job_from_args(parser.parse_args(["run", "m.py"]), "m.py").limit_ms == 60_000
