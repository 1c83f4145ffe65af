"""The runtime's API over the daemon: what the editor's completion and hover help are built from."""


def test_the_runtime_api_names_drivebase_straight_with_its_signature(viewer):
    response = viewer.get("/api/runtime/api")
    assert response.status_code == 200
    api = response.json()
    modules = {m["name"]: m for m in api["modules"]}
    drivebase = next(
        s for s in modules["openbricks.robotics.drivebase"]["symbols"] if s["name"] == "DriveBase"
    )
    straight = next(m for m in drivebase["members"] if m["name"] == "straight")
    assert straight["signature"] == "(distance_mm, then='coast', wait=True)"
    assert straight["doc"].startswith("Drive `distance_mm` forward")
    assert "openbricks.host_calls" not in modules and not any(
        n.split(".")[-1].startswith("_") for n in modules
    )
