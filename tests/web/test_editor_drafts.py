"""A team at the table: an edit in the Editor is kept by the console as it is typed (a page switch and a
reload find it again), a run's output shows under the editor, and a runtime error names the program and
marks its line, which a click on the traceback shows."""

from __future__ import annotations

import pytest

from tests.web.conftest import screenshot
from tests.web.test_console_pages import wait_for

pytestmark = pytest.mark.e2e

DIVIDE = "print('about to divide')\nx = 1\nprint(x / 0)\n"


def editor_text(page) -> str:
    return page.locator(".cm-content").inner_text()


def type_at_end(page, text: str) -> None:
    page.locator(".cm-content").click()
    page.keyboard.press("Control+End")
    page.keyboard.type(text)


def test_an_edit_survives_a_page_switch_and_a_reload_and_save_makes_a_version(console, page_for):
    with console.api() as api:
        assert api.put("/api/programs/keep.py", json={"source": "print('v1')\n"}).status_code == 200
    page = page_for(console.url)
    base = page.url.split("#")[0]
    page.goto(base + "#/editor?program=keep.py")
    page.locator("h1", has_text="keep.py").wait_for()

    # Typed, and at once another page: the edit is sent as the Editor is left, not lost with it.
    type_at_end(page, "# first edit")
    page.goto(base + "#/dashboard")
    page.locator("[data-testid=stop-all]").wait_for()
    with console.api() as api:
        draft = wait_for(
            lambda: api.get("/api/programs/keep.py/draft").json().get("source"), what="the draft was kept"
        )
    assert draft == "print('v1')\n# first edit"
    page.goto(base + "#/editor?program=keep.py")
    page.wait_for_function("() => document.querySelector('.cm-content')?.innerText.includes('# first edit')")
    assert "unsaved edit restored" in page.locator("[data-testid=draft-state]").inner_text()

    # Typed, and at once a reload: the page asks first (and sends the edit), and the edit is back.
    asked: list[str] = []

    def answer(dialog):
        asked.append(dialog.type)
        dialog.accept()

    page.on("dialog", answer)
    type_at_end(page, "\n# second edit")
    page.reload()
    page.locator("h1", has_text="keep.py").wait_for()
    page.wait_for_function("() => document.querySelector('.cm-content')?.innerText.includes('# second edit')")
    assert asked == ["beforeunload"]
    assert "# first edit" in editor_text(page)

    # Save makes version 2 of exactly that text and clears the draft.
    page.get_by_role("button", name="Save", exact=True).click()
    page.locator("[data-testid=draft-state]", has_text="v2").wait_for()
    with console.api() as api:
        stored = api.get("/api/programs/keep.py").json()
        assert stored["version"] == 2
        assert stored["source"] == "print('v1')\n# first edit\n# second edit"
        assert api.get("/api/programs/keep.py/draft").status_code == 404
    assert not page.errors  # type: ignore[attr-defined]


def test_a_run_shows_under_the_editor_and_a_runtime_error_marks_its_line(console, page_for):
    hub = sorted(h["name"] for h in console.wait_hubs_idle(2))[0]
    with console.api() as api:
        api.put("/api/programs/divide.py", json={"source": DIVIDE})
    page = page_for(console.url)
    page.goto(page.url.split("#")[0] + "#/editor?program=divide.py")
    page.locator("h1", has_text="divide.py").wait_for()
    page.locator("label.target", has_text=hub).locator("input").check()
    pane = page.locator(f"[data-testid=editor-output] [data-testid=output-pane][data-hub='{hub}']")
    pane.wait_for()
    page.click("[data-testid=run]")

    frame = pane.locator(".r.at", has_text='File "divide.py", line 3')
    frame.wait_for(timeout=60000)
    assert "about to divide" in pane.locator("[data-testid=terminal]").inner_text()
    assert "/program.py" not in pane.locator("[data-testid=terminal]").inner_text()
    marked = page.locator(".cm-line", has=page.locator(".cm-lintRange-error"))
    marked.wait_for()
    assert marked.inner_text() == "print(x / 0)"
    error = page.locator("[data-testid=runtime-error]")
    assert "divide.py, line 3" in error.inner_text() and "ZeroDivisionError" in error.inner_text()
    screenshot(page, "editor-runtime-error")

    # A click on the traceback's line puts the cursor on that line of the program.
    on_line_3 = "() => document.querySelector('.cm-activeLine')?.innerText === 'print(x / 0)'"
    frame.click()
    page.wait_for_function(on_line_3, timeout=5000)

    # On the Output page too: the click opens the program in the Editor at that line.
    page.goto(page.url.split("#")[0] + "#/output")
    page.locator(f"[data-testid=output-pane][data-hub='{hub}'] .r.at", has_text="divide.py").click()
    page.locator("h1", has_text="divide.py").wait_for()
    page.wait_for_function(on_line_3, timeout=5000)
    assert not page.errors  # type: ignore[attr-defined]
