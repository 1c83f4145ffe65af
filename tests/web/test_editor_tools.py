"""The Editor as a team lives in it, on a real console with virtual hubs: completion and hover help for the
runtime's API, a program's versions compared and restored, rename, export, import and delete, and a REPL
on a hub."""

from __future__ import annotations

import pytest

from tests.web.conftest import screenshot
from tests.web.test_console_pages import wait_for

pytestmark = pytest.mark.e2e

V1 = "from openbricks.robotics import DriveBase\nrobot = DriveBase(None, None, 56, 114)\n"
V2 = V1 + "print('v2')\n"


def test_completion_versions_file_operations_and_the_repl_in_the_page(console, page_for, tmp_path):
    hubs = console.wait_hubs_idle(2)
    with console.api() as api:
        for text in (V1, V2):
            assert api.put("/api/programs/drive.py", json={"source": text}).status_code == 200
    page = page_for(console.url.split("#")[0] + "#/editor?program=drive.py")
    page.on("dialog", lambda dialog: dialog.accept())
    page.locator("h1", has_text="drive.py").wait_for()

    # Completion from the runtime's own API: `robot.str` offers DriveBase.straight with its signature.
    page.locator(".cm-content").click()
    page.keyboard.press("Control+End")
    page.keyboard.type("robot.str")
    popup = page.locator(".cm-tooltip-autocomplete")
    popup.wait_for()
    wait_for(
        lambda: "(distance_mm, then='coast', wait=True)" in popup.inner_text(), what="straight's signature"
    )
    assert "straight" in popup.inner_text()
    screenshot(page, "editor-completion")
    page.keyboard.press("Enter")
    page.keyboard.type("(100)\nDriveBase.")
    page.keyboard.press("Control+Space")
    wait_for(lambda: "straight" in popup.inner_text(), what="DriveBase. offering straight")
    page.keyboard.press(
        "Backspace"
    )  # closes the list without Esc (Esc belongs to STOP ALL outside the editor)
    page.keyboard.press("Backspace")
    assert "robot.straight(100)" in page.locator(".cm-content").inner_text()
    # Hover help: the method's class, signature and summary.
    page.locator(".cm-line", has_text="robot.straight(100)").get_by_text("straight", exact=False).hover(
        position={"x": 50, "y": 5}
    )
    hover = page.locator(".cm-tooltip-hover")
    hover.wait_for()
    assert "DriveBase.straight(distance_mm, then='coast', wait=True)" in hover.inner_text()
    assert "forward" in hover.inner_text()

    # Versions: v1 compared with the editor's text, then restored as the newest version.
    page.click("[data-testid=show-versions]")
    versions = page.locator("[data-testid=version]")
    wait_for(lambda: versions.count() == 2, what="two versions listed")
    versions.filter(has_text="v1").click()
    diff = page.locator("[data-testid=version-diff]")
    wait_for(lambda: "+ robot.straight(100)" in diff.inner_text(), what="the diff against the editor")
    assert (
        "+ print('v2')" in diff.inner_text()
        and "  robot = DriveBase(None, None, 56, 114)" in diff.inner_text()
    )
    screenshot(page, "editor-versions")
    page.click("[data-testid=restore-version]")
    page.locator("[data-testid=versions]").wait_for(state="detached")
    with console.api() as api:
        restored = wait_for(lambda: api.get("/api/programs/drive.py").json(), what="the restored version")
        assert (restored["version"], restored["source"]) == (3, V1)

    # Rename: the program and its versions go to the new name.
    page.get_by_role("button", name="Rename").click()
    page.fill("[data-testid=rename-input]", "drive2.py")
    page.locator("[data-testid=program-manager]").get_by_role("button", name="Rename").click()
    page.locator("h1", has_text="drive2.py").wait_for()
    with console.api() as api:
        assert api.get("/api/programs/drive.py").status_code == 404
        assert [v["version"] for v in api.get("/api/programs/drive2.py/versions").json()] == [3, 2, 1]

    # Export downloads the stored text.
    with page.expect_download() as download:
        page.click("[data-testid=export]")
    assert download.value.suggested_filename == "drive2.py"
    assert open(download.value.path(), encoding="utf-8").read() == V1

    # Import a .py from disk; importing it again adds a version after the page asks.
    disk = tmp_path / "from_disk.py"
    disk.write_text("print('from disk')\n")
    page.set_input_files("[data-testid=import-file]", str(disk))
    page.locator("h1", has_text="from_disk.py").wait_for()
    disk.write_text("print('from disk, again')\n")
    page.set_input_files("[data-testid=import-file]", str(disk))
    # Waited for through the page: Playwright answers the page's question only while it is called.
    page.locator("button.prog", has_text="from_disk.py").get_by_text("v2").wait_for()
    with console.api() as api:
        assert api.get("/api/programs/from_disk.py").json()["source"] == "print('from disk, again')\n"

    # Delete, after the page asks.
    page.locator("[data-testid=program-manager]").get_by_role("button", name="Delete").click()
    page.locator("h1", has_text="No program open").wait_for()
    with console.api() as api:
        assert api.get("/api/programs/from_disk.py").status_code == 404

    # The REPL on a virtual hub: 1+1 is 2.
    page.goto(console.url.split("#")[0] + "#/editor?program=drive2.py")
    page.locator("h1", has_text="drive2.py").wait_for()
    page.click("[data-testid=repl-tab]")
    page.locator("[data-testid=repl-hub]").select_option(hubs[0]["hub_id"])
    page.fill("[data-testid=repl-input]", "1+1")
    page.press("[data-testid=repl-input]", "Enter")
    output = page.locator("[data-testid=repl-output]")
    output.wait_for()
    assert output.inner_text() == "2"
    for entry in ("x = 6 * 7", "x"):  # an entry waits for the one before it to be answered
        page.locator("[data-testid=repl][data-pending=false]").wait_for()
        page.fill("[data-testid=repl-input]", entry)
        page.press("[data-testid=repl-input]", "Enter")
    page.locator("[data-testid=repl][data-pending=false]").wait_for()
    wait_for(lambda: output.count() == 2, what="the second value")
    assert output.nth(1).inner_text() == "42"
    screenshot(page, "editor-repl")
    page.set_viewport_size({"width": 390, "height": 844})
    page.locator("[data-testid=repl-output]").last.scroll_into_view_if_needed()
    screenshot(page, "editor-repl-phone")
    assert not page.errors  # type: ignore[attr-defined]
