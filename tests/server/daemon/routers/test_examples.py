"""The examples over the API: listed with their groups, and opened as a new stored program (a copy)."""

from pathlib import Path

EXAMPLES = Path(__file__).resolve().parents[4] / "examples"


def test_examples_are_listed_with_their_group_and_summary(viewer):
    listed = viewer.get("/api/examples").json()
    square = next(e for e in listed if e["id"] == "drivebase_square")
    assert square["group"] == "drive_base" and square["group_title"] == "Drive base"
    assert square["file"] == "drivebase_square.py" and square["summary"] and square["title"]
    assert {e["group"] for e in listed} == {"drive_base", "sensors", "line_following", "competition"}
    one = viewer.get("/api/examples/drivebase_square").json()
    assert one["source"] == (EXAMPLES / "drivebase_square.py").read_text()


def test_opening_an_example_stores_a_copy_under_a_free_name(operator):
    first = operator.post("/api/examples/drivebase_square/open")
    assert first.status_code == 201, first.text
    assert first.json()["program"]["name"] == "drivebase_square.py"
    assert first.json()["program"]["version"] == 1
    operator.put("/api/programs/drivebase_square.py", json={"source": "print('mine')\n"})
    second = operator.post("/api/examples/drivebase_square/open", json={}).json()
    assert second["program"]["name"] == "drivebase_square-2.py"
    # the team's edit of the first copy is untouched, the new copy is the example as shipped
    assert operator.get("/api/programs/drivebase_square.py").json()["source"] == "print('mine')\n"
    shipped = (EXAMPLES / "drivebase_square.py").read_text()
    assert operator.get("/api/programs/drivebase_square-2.py").json()["source"] == shipped
    named = operator.post("/api/examples/first_robot/open", json={"name": "lap.py"}).json()
    assert named["program"]["name"] == "lap.py"
    taken = operator.post("/api/examples/first_robot/open", json={"name": "lap.py"})
    assert taken.status_code == 409 and taken.json()["error"] == "program_exists"


def test_an_unknown_example_and_a_viewer_are_refused(operator, viewer):
    missing = operator.post("/api/examples/nope/open")
    assert missing.status_code == 404 and missing.json()["error"] == "not_found"
    assert viewer.post("/api/examples/drivebase_square/open").status_code == 403
    assert operator.get("/api/programs").json() == []
