"""Stored programs over the API: versions, and bad input refused with a specific error before storing."""

import pytest


def test_programs_are_stored_with_their_versions(operator):
    first = operator.put("/api/programs/square.py", json={"source": "print('v1')\n"}).json()
    same = operator.put("/api/programs/square.py", json={"source": "print('v1')\n"}).json()
    second = operator.put("/api/programs/square.py", json={"source": "print('v2')\n"}).json()
    assert (first["created"], same["created"], second["created"]) == (True, False, True)
    assert second["program"]["version"] == 2 and second["program"]["who"] == "local"
    assert operator.get("/api/programs/square.py").json()["source"] == "print('v2')\n"
    assert operator.get("/api/programs/square.py/versions/1").json()["source"] == "print('v1')\n"
    assert [v["version"] for v in operator.get("/api/programs/square.py/versions").json()] == [2, 1]
    assert [p["name"] for p in operator.get("/api/programs").json()] == ["square.py"]
    assert operator.delete("/api/programs/square.py").status_code == 204
    assert operator.get("/api/programs/square.py").json()["error"] == "not_found"


def test_a_syntax_error_names_file_line_and_column_and_nothing_is_stored(operator):
    refused = operator.put("/api/programs/bad.py", json={"source": "x = 1\nif x\n    pass\n"})
    assert refused.status_code == 422
    error = refused.json()
    assert error["error"] == "syntax_error"
    assert error["message"].startswith("bad.py, line 2:") and "if x" in error["message"]
    assert error["detail"]["line"] == 2 and error["detail"]["column"] and error["hint"]
    assert operator.get("/api/programs/bad.py").status_code == 404


def test_the_syntax_check_never_runs_the_program(operator, tmp_path):
    marker = tmp_path / "ran"
    source = f"open({str(marker)!r}, 'w').write('x')\n"
    assert operator.put("/api/programs/p.py", json={"source": source}).status_code == 200
    assert not marker.exists()


@pytest.mark.parametrize(
    "name, status",
    [
        ("..", 404),  # the client resolves it to /api: it never reaches the route
        ("..%2F..%2Fetc%2Fpasswd", 404),
        ("a..b", 422),
        (".hidden", 422),
        ("x" * 65, 422),
        ("sp ace.py", 422),
        ("-x.py", 422),
        ("ok_name-1.py", 200),
    ],
)
def test_program_names_are_checked(operator, name, status):
    response = operator.put(f"/api/programs/{name}", json={"source": "pass\n"})
    assert response.status_code == status, response.text
    if status == 422:
        assert response.json()["error"] == "bad_program_name"


def test_oversized_binary_and_non_text_programs_are_refused(operator):
    big = operator.put("/api/programs/big.py", json={"source": "#" * (256 * 1024 + 1)})
    assert big.status_code == 413 and big.json()["error"] == "program_too_large"
    binary = operator.put("/api/programs/bin.py", json={"source": "print(1)\n\x00\x01\x02"})
    assert binary.status_code == 422 and binary.json()["error"] == "binary_program"
    assert "line 2" in binary.json()["message"]
    surrogate = operator.put(
        "/api/programs/s.py",
        content=b'{"source": "x = 1\\n\\ud800"}',
        headers={"content-type": "application/json"},
    )
    assert surrogate.status_code == 422 and surrogate.json()["error"] in ("not_utf8", "invalid_request")
    deep = operator.put("/api/programs/deep.py", json={"source": "x = " + "(" * 5000 + ")" * 5000 + "\n"})
    assert deep.status_code == 422 and deep.json()["error"] in ("syntax_error", "program_too_complex")


def test_malformed_requests_get_the_error_shape(operator):
    broken = operator.put(
        "/api/programs/a.py", content=b"{not json", headers={"content-type": "application/json"}
    )
    assert broken.status_code == 422 and broken.json()["error"] == "invalid_request"
    assert "JSON" in broken.json()["message"]
    missing = operator.put("/api/programs/a.py", json={"text": "x"})
    assert missing.status_code == 422 and missing.json()["message"].startswith("source:")
    wrong_method = operator.post("/api/programs/a.py", json={"source": "x"})
    assert wrong_method.status_code == 405 and set(wrong_method.json()) >= {"error", "message"}


def test_rename_moves_every_version_and_refuses_taken_and_bad_names(operator):
    operator.put("/api/programs/a.py", json={"source": "print(1)\n"})
    operator.put("/api/programs/a.py", json={"source": "print(2)\n"})
    operator.put("/api/programs/b.py", json={"source": "print(3)\n"})
    renamed = operator.post("/api/programs/a.py/rename", json={"new_name": "c.py"})
    assert renamed.status_code == 200 and renamed.json()["name"] == "c.py" and renamed.json()["version"] == 2
    assert [v["version"] for v in operator.get("/api/programs/c.py/versions").json()] == [2, 1]
    assert operator.get("/api/programs/a.py").status_code == 404
    taken = operator.post("/api/programs/c.py/rename", json={"new_name": "b.py"})
    assert taken.status_code == 409 and taken.json()["error"] == "program_exists" and taken.json()["hint"]
    bad = operator.post("/api/programs/c.py/rename", json={"new_name": "../x.py"})
    assert bad.status_code == 422 and bad.json()["error"] == "bad_program_name"
    missing = operator.post("/api/programs/nope.py/rename", json={"new_name": "d.py"})
    assert missing.status_code == 404 and missing.json()["error"] == "not_found"
    assert operator.post("/api/programs/c.py/rename", json={"new_name": "c.py"}).status_code == 200


def test_import_never_overwrites_unless_asked_and_download_gives_the_file(operator):
    imported = operator.post("/api/programs", json={"name": "disk.py", "source": "print('from disk')\n"})
    assert imported.status_code == 201 and imported.json()["program"]["version"] == 1
    again = operator.post("/api/programs", json={"name": "disk.py", "source": "print('other')\n"})
    assert again.status_code == 409 and again.json()["error"] == "program_exists"
    replaced = operator.post("/api/programs", json={"name": "disk.py", "source": "x = 2\n", "replace": True})
    assert replaced.status_code == 201 and replaced.json()["program"]["version"] == 2
    bad = operator.post("/api/programs", json={"name": "a b.py", "source": "pass\n"})
    assert bad.status_code == 422 and bad.json()["error"] == "bad_program_name"
    broken = operator.post("/api/programs", json={"name": "broken.py", "source": "if x\n"})
    assert broken.status_code == 422 and broken.json()["error"] == "syntax_error"
    file = operator.get("/api/programs/disk.py/download")
    assert file.status_code == 200 and file.text == "x = 2\n"
    assert file.headers["content-disposition"] == 'attachment; filename="disk.py"'
    assert operator.get("/api/programs/disk.py/download?version=1").text == "print('from disk')\n"
    assert operator.get("/api/programs/disk.py/download?version=9").status_code == 404


def test_restoring_a_version_makes_its_text_the_newest(operator):
    for text in ("v = 1\n", "v = 2\n", "v = 3\n"):
        operator.put("/api/programs/r.py", json={"source": text})
    restored = operator.post("/api/programs/r.py/versions/1/restore").json()
    assert restored["created"] and restored["program"]["version"] == 4
    assert operator.get("/api/programs/r.py").json()["source"] == "v = 1\n"
    assert operator.post("/api/programs/r.py/versions/7/restore").status_code == 404


def test_a_viewer_reads_and_downloads_but_changes_nothing(operator, viewer):
    operator.put("/api/programs/mine.py", json={"source": "pass\n"})
    assert viewer.get("/api/programs/mine.py/download").status_code == 200
    refused = [
        viewer.post("/api/programs", json={"name": "v.py", "source": "pass\n"}),
        viewer.post("/api/programs/mine.py/rename", json={"new_name": "theirs.py"}),
        viewer.post("/api/programs/mine.py/versions/1/restore"),
        viewer.delete("/api/programs/mine.py"),
    ]
    assert [r.status_code for r in refused] == [403] * 4
    assert [p["name"] for p in operator.get("/api/programs").json()] == ["mine.py"]


def test_a_draft_is_kept_as_typed_and_saving_the_program_clears_it(operator):
    """The editor's unsaved text: unchecked (half-typed code is fine), one per name, there for a new
    program before its first save, moved by a rename, cleared by a save and a delete."""
    assert operator.get("/api/programs/new.py/draft").json()["error"] == "not_found"
    typed = operator.put("/api/programs/new.py/draft", json={"source": "while True\n"})
    assert typed.status_code == 200, typed.text
    assert typed.json()["base_version"] is None and typed.json()["who"] == "local"
    again = operator.put("/api/programs/new.py/draft", json={"source": "while True:\n    pass\n"}).json()
    assert operator.get("/api/programs/new.py/draft").json()["source"] == "while True:\n    pass\n"
    assert operator.get("/api/drafts").json() == [{k: v for k, v in again.items() if k != "source"}]
    assert operator.get("/api/programs").json() == []  # a draft is not a program
    operator.put("/api/programs/new.py", json={"source": "pass\n"})
    assert operator.get("/api/programs/new.py/draft").status_code == 404
    operator.put("/api/programs/new.py/draft", json={"source": "x = 1\n", "base_version": 1})
    operator.post("/api/programs/new.py/rename", json={"new_name": "old.py"})
    moved = operator.get("/api/programs/old.py/draft").json()
    assert (moved["source"], moved["base_version"]) == ("x = 1\n", 1)
    operator.post("/api/programs/old.py/versions/1/restore")  # the restored text is what is edited now
    assert operator.get("/api/programs/old.py/draft").status_code == 404
    operator.put("/api/programs/old.py/draft", json={"source": "z = 1\n"})
    assert operator.delete("/api/programs/old.py/draft").status_code == 204
    assert operator.delete("/api/programs/old.py/draft").status_code == 204  # nothing left is fine
    operator.put("/api/programs/old.py/draft", json={"source": "y = 2\n"})
    operator.delete("/api/programs/old.py")
    assert operator.get("/api/drafts").json() == []


def test_a_draft_refuses_bad_names_and_versions_and_a_viewer_cannot_write_one(operator, viewer):
    assert operator.put("/api/programs/..%2Fx/draft", json={"source": ""}).status_code in (400, 404, 422)
    bad = operator.put("/api/programs/a%20b.py/draft", json={"source": ""})
    assert bad.json()["error"] == "bad_program_name"
    assert operator.put("/api/programs/a.py/draft", json={"source": "", "base_version": 0}).status_code == 422
    operator.put("/api/programs/a.py/draft", json={"source": "mine\n"})
    refused = [
        viewer.put("/api/programs/a.py/draft", json={"source": "theirs\n"}),
        viewer.delete("/api/programs/a.py/draft"),
    ]
    assert [r.status_code for r in refused] == [403, 403]
    assert viewer.get("/api/programs/a.py/draft").json()["source"] == "mine\n"
    assert [d["name"] for d in viewer.get("/api/drafts").json()] == ["a.py"]
