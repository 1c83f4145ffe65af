"""A first-time visitor's first minutes: the Editor offers the manual's examples before anything else,
one opens as a program of the visitor's own, and it runs on a virtual hub from the page."""

from __future__ import annotations

import pytest

from tests.web.conftest import screenshot
from tests.web.test_console_pages import pane_text, wait_for

pytestmark = pytest.mark.e2e

SQUARE = "drivebase_square"


def test_a_first_time_visitor_opens_an_example_and_runs_it_on_a_virtual_hub(console, page_for):
    hubs = console.wait_hubs_idle(2)
    hub = sorted(h["name"] for h in hubs)[0]
    with console.api() as api:
        assert api.get("/api/programs").json() == [], "this console is meant to be fresh"
        shipped = api.get(f"/api/examples/{SQUARE}").json()["source"]
    page = page_for(console.url)

    # The dashboard points a console with hubs and no runs at the examples.
    page.locator("[data-testid=no-runs]").wait_for()
    page.locator("[data-testid=no-runs] button", has_text="examples").click()

    gallery = page.locator("[data-testid=examples]")
    gallery.wait_for()
    for group in ("Drive base", "Sensors", "Line following", "Competition"):
        assert gallery.get_by_role("heading", name=group, exact=True).count() == 1, group
    card = gallery.locator(f"[data-testid=example][data-example={SQUARE}]")
    assert "Drive a square" in card.inner_text()
    screenshot(page, "editor-examples")

    # A fresh visit to the Editor itself shows them first too.
    page.goto(page.url.split("#")[0] + "#/editor")
    card.get_by_role("button", name="Open").click()
    page.locator("h1", has_text=f"{SQUARE}.py").wait_for()
    page.wait_for_selector(".cm-content")
    assert "DriveBase" in page.locator(".cm-content").inner_text()
    with console.api() as api:
        stored = api.get(f"/api/programs/{SQUARE}.py").json()
    assert stored["source"] == shipped and stored["version"] == 1

    page.locator("label.target", has_text=hub).locator("input").check()
    page.click("[data-testid=run]")
    page.goto(page.url.split("#")[0] + "#/output")
    page.wait_for_function(
        "(name) => /side 4[\\s\\S]*done/.test(document.querySelector("
        "`[data-testid=output-pane][data-hub='${name}'] [data-testid=terminal]`)?.innerText ?? '')",
        arg=hub,
        timeout=90000,
    )
    assert "side 1" in pane_text(page, hub)
    with console.api() as api:
        finished = wait_for(
            lambda: [
                r
                for r in api.get("/api/runs").json()
                if r["program_name"] == f"{SQUARE}.py" and r["outcome"] == "finished"
            ],
            timeout_s=90,
            what="the example's run finished",
        )
        # The example stays as shipped: opening it again gives a second copy, not the edited one.
        assert api.get(f"/api/examples/{SQUARE}").json()["source"] == shipped
    assert finished[0]["hub_id"] in {h["hub_id"] for h in hubs}
    assert not page.errors  # type: ignore[attr-defined]
