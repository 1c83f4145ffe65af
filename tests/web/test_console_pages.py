"""The browser console as a person uses it: Debian's Chromium, signed in with the URL `openbricks console`
printed, against the real daemon with two virtual hubs. Every page is visited and screenshotted (kept in
build/artifacts/web/); the flows a team at the table relies on are driven through the page itself."""

from __future__ import annotations

import re
import time

import pytest

from tests.web.conftest import screenshot

pytestmark = pytest.mark.e2e

COUNTING = """from openbricks.tools import wait

for i in range(20):
    print("count", i)
    wait(20)
print("\\x1b[32mdone counting\\x1b[0m")  # in green, as a terminal shows it
"""

LONG_LINES = 150
LONG_COUNT = f"""from openbricks.tools import wait

for i in range({LONG_LINES}):
    print("long", i)
    wait(20)
print("long done")
"""


def printing_forever(word: str, every_ms: int) -> str:
    """A program that prints `word N` every `every_ms` until it is stopped."""
    return f"""from openbricks.tools import wait

i = 0
while True:
    print("{word}", i)
    i += 1
    wait({every_ms})
"""


FOREVER = printing_forever("still going", 100)


RECORD_SOCKETS = """(() => {
    const Native = window.WebSocket;
    window.__sockets = [];
    window.WebSocket = class extends Native {
        constructor(...args) { super(...args); window.__sockets.push(this); }
    };
})()"""


def open_program(page, name: str, source: str) -> None:
    """Create (or open) a program in the editor and replace its text."""
    page.goto(page.url.split("#")[0] + "#/editor")
    existing = page.locator("button.prog", has_text=name)
    if existing.count():
        existing.first.click()
    else:
        page.fill("input[aria-label='New program name']", name)
        page.click("form.new button[type=submit]")
    page.wait_for_selector(".cm-content")
    page.click(".cm-content")
    page.keyboard.press("Control+a")
    page.keyboard.press("Delete")
    # CodeMirror auto-indents typed newlines: insert the text as one paste instead.
    page.evaluate(
        """(text) => {
            const dt = new DataTransfer();
            dt.setData('text/plain', text);
            document.querySelector('.cm-content').dispatchEvent(
                new ClipboardEvent('paste', {clipboardData: dt, bubbles: true, cancelable: true}));
        }""",
        source,
    )


def select_all_hubs(page) -> None:
    page.click("text=all hubs")


def runs(console) -> list[dict]:
    with console.api() as c:
        return c.get("/api/runs").json()


def wait_for(predicate, timeout_s: float = 30, what: str = "condition"):
    deadline = time.monotonic() + timeout_s
    while time.monotonic() < deadline:
        value = predicate()
        if value:
            return value
        time.sleep(0.2)
    raise AssertionError(f"timed out waiting for {what}")


def pane_text(page, hub_name: str) -> str:
    return page.locator(
        f"[data-testid=output-pane][data-hub='{hub_name}'] [data-testid=terminal]"
    ).inner_text()


def downloaded_output(page, hub_name: str) -> str:
    """What a terminal holds, all of it, through its Download button (the screen shows only the tail)."""
    with page.expect_download() as download:
        page.locator(f"[data-testid=output-pane][data-hub='{hub_name}']").get_by_role(
            "button", name="Download"
        ).click()
    return open(download.value.path()).read()


def test_a_syntax_error_is_marked_at_its_line_and_nothing_is_sent(console, page_for):
    page = page_for(console.url)
    before = runs(console)
    open_program(page, "broken.py", "print('fine')\nx = (1,\nprint('never')\n")
    select_all_hubs(page)
    page.click("[data-testid=run]")
    problems = page.wait_for_selector("[data-testid=problems]")
    assert "line 2" in problems.inner_text()
    # The mark sits on the editor's line 2 itself.
    marked = page.locator(".cm-line", has=page.locator(".cm-lintRange-error"))
    assert marked.count() == 1
    assert marked.inner_text().startswith("x = (1,")
    screenshot(page, "editor-syntax-error")
    assert runs(console) == before, "a program with a syntax error reached a hub"
    with console.api() as c:
        assert all(h["status"] == "idle" for h in c.get("/api/hubs").json()["hubs"])


def test_two_hubs_run_at_once_each_terminal_shows_its_own_output_and_history_keeps_both(console, page_for):
    page = page_for(console.url)
    hubs = console.wait_hubs_idle(2)
    names = sorted(h["name"] for h in hubs)
    open_program(page, "count.py", COUNTING)
    select_all_hubs(page)
    page.click("[data-testid=run]")
    page.goto(page.url.split("#")[0] + "#/output")
    for name in names:
        page.wait_for_function(
            "(name) => document.querySelector("
            "`[data-testid=output-pane][data-hub='${name}'] [data-testid=terminal]`)"
            "?.innerText.includes('done counting')",
            arg=name,
            timeout=60000,
        )
    for name in names:
        text = pane_text(page, name)
        counts = [int(n) for n in re.findall(r"count (\d+)", text)]
        assert counts == list(range(20)), f"{name}: {counts}"
        pane = page.locator(f"[data-testid=output-pane][data-hub='{name}']")
        assert pane.locator("span.f2", has_text="done counting").count() == 1, "the ANSI green is lost"
        assert "\x1b" not in text and "[32m" not in text
    # Search finds a line and marks it.
    pane = page.locator(f"[data-testid=output-pane][data-hub='{names[0]}']")
    pane.get_by_role("searchbox").fill("COUNT 7")
    pane.get_by_role("searchbox").press("Enter")
    pane.locator(".mk", has_text="count 7").wait_for()
    screenshot(page, "output-two-hubs")

    finished = wait_for(
        lambda: [r for r in runs(console) if r["program_name"] == "count.py" and r["outcome"] == "finished"],
        what="both runs finished in the history",
    )
    assert sorted({r["hub_id"] for r in finished}) == sorted(h["hub_id"] for h in hubs)

    page.goto(page.url.split("#")[0] + "#/history")
    rows = page.locator("[data-testid=run-row]", has_text="count.py")
    rows.first.wait_for()
    assert rows.count() >= 2
    for name in names:
        assert page.locator("[data-testid=run-row]", has_text=name).count() >= 1
    rows.first.click()
    output = page.wait_for_selector("[data-testid=run-output]")
    page.wait_for_function(
        "() => document.querySelector('[data-testid=run-output]').innerText.includes('done counting')"
    )
    assert "count 19" in output.inner_text() and "[32m" not in output.inner_text()
    page.locator("[data-testid=run-output] span.f2", has_text="done counting").wait_for()  # still green
    screenshot(page, "history-run")

    page.goto(page.url.split("#")[0] + "#/dashboard")
    for name in names:
        tile = page.locator(f"[data-testid=hub-tile][data-hub='{name}']")
        tile.locator("[data-testid=last-outcome]", has_text="finished").wait_for()
    screenshot(page, "dashboard")


def test_stop_all_from_the_keyboard_stops_every_hub(console, page_for):
    page = page_for(console.url)
    hubs = console.wait_hubs_idle(2)
    open_program(page, "forever.py", FOREVER)
    select_all_hubs(page)
    page.click("[data-testid=run]")
    page.goto(page.url.split("#")[0] + "#/dashboard")
    for h in hubs:
        page.locator(
            f"[data-testid=hub-tile][data-hub='{h['name']}'] [data-testid=hub-status]", has_text="running"
        ).wait_for()
    page.locator("[data-testid=run-timer]").first.wait_for()
    screenshot(page, "dashboard-running")
    page.keyboard.press("Escape")
    for h in hubs:
        tile = page.locator(f"[data-testid=hub-tile][data-hub='{h['name']}']")
        tile.locator("[data-testid=hub-status]", has_text="idle").wait_for(timeout=15000)
        tile.locator("[data-testid=last-outcome]", has_text="stopped").wait_for()
    stopped = [r for r in runs(console) if r["program_name"] == "forever.py"]
    assert len(stopped) == 2 and all(r["outcome"] == "stopped" for r in stopped), stopped


def test_a_viewer_sees_everything_and_can_change_nothing(console, page_for):
    with console.api() as c:
        c.put(
            "/api/programs/shown.py", json={"source": "print('a viewer may read this')\n"}
        ).raise_for_status()
    token = console.mint("viewer")
    page = page_for(console.sign_in_url(token))
    page.locator(".role", has_text="viewer").wait_for()
    assert page.is_disabled("[data-testid=stop-all]")
    page.locator("[data-testid=readonly-reason]").wait_for()
    assert "Viewer role" in page.inner_text("[data-testid=readonly-reason]")
    tiles = page.locator("[data-testid=hub-tile]")
    tiles.first.wait_for()
    for button in tiles.locator("footer button").all():
        assert button.is_disabled(), button.inner_text()
        assert "Viewer role" in (button.get_attribute("title") or "")
    screenshot(page, "dashboard-viewer")

    before = runs(console)
    page.keyboard.press("Escape")  # STOP ALL's key: refused with the reason, nothing sent
    page.locator(".notice", has_text="Viewer role").first.wait_for()

    page.goto(page.url.split("#")[0] + "#/editor")
    page.locator("button.prog", has_text="shown.py").click()
    for label in ("Save", "Upload", "Run ▶", "Stop"):
        assert page.get_by_role("button", name=label, exact=True).is_disabled(), label
    assert page.is_disabled("input[aria-label='New program name']")
    screenshot(page, "editor-viewer")
    assert runs(console) == before
    # History and output stay readable.
    page.goto(page.url.split("#")[0] + "#/history")
    page.wait_for_function(
        "(n) => document.querySelectorAll('[data-testid=run-row]').length === n", arg=len(runs(console))
    )


PAGES = [
    ("dashboard", "Dashboard"),
    ("editor", "Programs"),
    ("output", "Output"),
    ("history", "History"),
    ("telemetry", "Telemetry"),
    ("sim", "Simulator"),
    ("flash", "Flash"),
    ("servo", "Servo-ID"),
    ("audit", "Audit"),
    ("share", "Share"),
]


@pytest.mark.parametrize(("width", "height"), [(1280, 800), (820, 1180)], ids=["laptop", "tablet"])
def test_every_page_renders_with_content(console, page_for, width, height):
    page = page_for(console.url, width, height)
    for page_id, expect in PAGES:
        page.goto(f"{console.base}/#/{page_id}")
        page.locator("main h1, main h3").filter(has_text=expect).first.wait_for()
        page.wait_for_timeout(300)
        # Nothing wider than the window: the page works at this width without sideways scrolling.
        overflow = page.evaluate("() => document.documentElement.scrollWidth - window.innerWidth")
        assert overflow <= 1, f"{page_id} at {width}px is {overflow}px too wide"
        screenshot(page, f"{page_id}-{width}x{height}")
    assert page.errors == [], page.errors


def test_a_dropped_event_stream_resumes_without_losing_or_repeating_a_line(console, browser, page_for):
    hubs = console.wait_hubs_idle(2)
    name = hubs[0]["name"]
    context = browser.new_context(viewport={"width": 1280, "height": 800})
    try:
        context.add_init_script(RECORD_SOCKETS)
        page = context.new_page()
        page.goto(console.url)
        page.wait_for_selector("[data-testid=stop-all]")
        open_program(page, "long_count.py", LONG_COUNT)
        assert page.is_disabled("[data-testid=run]"), "Run with no target picked"
        page.locator("label.target", has_text=name).locator("input").check()
        page.click("[data-testid=run]")
        page.goto(page.url.split("#")[0] + "#/output")
        last_count = (
            "([name, n]) => Math.max(-1, ...[...(document.querySelector("
            "`[data-testid=output-pane][data-hub='${name}'] [data-testid=terminal]`)?.innerText ?? '')"
            ".matchAll(/long (\\d+)/g)].map((m) => +m[1])) >= n"
        )
        for cut in range(3):  # the stream drops three times while the hub prints
            page.wait_for_function(last_count, arg=[name, 30 * (cut + 1)])
            page.evaluate("() => window.__sockets.at(-1).close()")
            page.wait_for_timeout(300)
        page.wait_for_function(
            "(name) => document.querySelector("
            "`[data-testid=output-pane][data-hub='${name}'] [data-testid=terminal]`)"
            "?.innerText.includes('long done')",
            arg=name,
            timeout=60000,
        )
        assert page.evaluate("() => window.__sockets.length") >= 4
        text = downloaded_output(page, name)
        counts = [int(n) for n in re.findall(r"long (\d+)", text)]
        assert counts == list(range(LONG_LINES)), "lines lost or repeated across reconnects"
    finally:
        context.close()


SHOWN_LAST = (
    "([name, word]) => Math.max(-1, ...[...(document.querySelector("
    "`[data-testid=output-pane][data-hub='${name}'] [data-testid=terminal]`)?.innerText ?? '')"
    ".matchAll(new RegExp(word + ' (\\\\d+)', 'g'))].map((m) => +m[1]))"
)


BUSY = printing_forever("busy", 20)


def test_a_terminal_follows_until_its_reader_scrolls_up(console, page_for):
    """Regression: a scroll the view did not get from its reader (its own redraw's, the browser's) made
    it stop following for good; only the wheel, a key, a drag or a touch may let go of the bottom."""
    page = page_for(console.url)
    name = console.wait_hubs_idle(2)[0]["name"]
    open_program(page, "busy.py", BUSY)
    page.locator("label.target", has_text=name).locator("input").check()
    page.click("[data-testid=run]")
    page.goto(page.url.split("#")[0] + "#/output")
    pane = page.locator(f"[data-testid=output-pane][data-hub='{name}']")
    scroller = pane.locator("[data-testid=terminal] > div").first
    try:
        # Enough lines to scroll: more than the pane has rows.
        # Asked of the pane on show each time (not a handle to the element of the moment).
        page.wait_for_function(
            "(sel) => { const el = document.querySelector(sel);"
            " return el && el.scrollHeight > 2 * el.clientHeight; }",
            arg=f"[data-testid=output-pane][data-hub='{name}'] [data-testid=terminal] > div",
        )
        # A scroll nobody asked for: the view goes back to the bottom and keeps following.
        scroller.evaluate("(el) => { el.scrollTop = 0; }")
        seen = page.evaluate(SHOWN_LAST, [name, "busy"])
        page.wait_for_function(f"(n) => ({SHOWN_LAST})(n) >= {seen + 10}", arg=[name, "busy"])
        # The reader turns the wheel up: the view holds still while the hub goes on printing.
        scroller.hover()
        page.mouse.wheel(0, -3000)
        page.wait_for_timeout(700)
        held = page.evaluate(SHOWN_LAST, [name, "busy"])
        page.wait_for_timeout(1500)
        assert page.evaluate(SHOWN_LAST, [name, "busy"]) == held, "scrolled up, yet it moved on"
        # Back down to the bottom: following again.
        page.mouse.wheel(0, 100000)
        page.wait_for_function(f"(n) => ({SHOWN_LAST})(n) >= {held + 10}", arg=[name, "busy"])
    finally:
        page.click("[data-testid=stop-all]")


PLOTTING = """from openbricks.tools import plot, wait

for i in range(40):
    plot("speed", i * 10)
    plot("heading", 90 - i)
    print("sample", i)
    wait(25)
"""


def test_telemetry_from_plot_is_drawn_live_and_kept_with_the_run(console, page_for):
    page = page_for(console.url)
    hub = console.wait_hubs_idle(2)[0]
    open_program(page, "plotting.py", PLOTTING)
    page.locator("label.target", has_text=hub["name"]).locator("input").check()
    page.click("[data-testid=run]")
    page.goto(page.url.split("#")[0] + "#/telemetry")
    card = page.locator("[data-testid=telemetry-card]", has_text=hub["name"])
    card.wait_for()
    # uPlot's legend names each series once it has samples.
    card.locator(".u-legend", has_text="speed").wait_for()
    card.locator(".u-legend", has_text="heading").wait_for()
    card.locator("canvas").first.wait_for()
    card.locator(".badge", has_text="finished").wait_for(timeout=30000)
    screenshot(page, "telemetry-live")
    # Kept with the run: the history's telemetry tab draws it again from the store.
    run = wait_for(lambda: [r for r in runs(console) if r["program_name"] == "plotting.py"], what="the run")[
        0
    ]
    with console.api() as c:
        samples = c.get(f"/api/runs/{run['run_id']}/telemetry").json()
    assert {s["name"] for s in samples} == {"speed", "heading"} and len(samples) == 80
    page.goto(page.url.split("#")[0] + f"#/history?run={run['run_id']}")
    page.get_by_role("tab", name="telemetry").click()
    page.locator("[data-testid=run-detail] .u-legend", has_text="heading").wait_for()
    screenshot(page, "history-telemetry")


def test_competition_mode_locks_uploads_while_a_run_is_on_and_keys_work(console, page_for):
    page = page_for(console.url)
    hubs = console.wait_hubs_idle(2)
    name, other = hubs[0]["name"], hubs[1]["name"]
    try:
        _competition_mode_locks_uploads(console, page_for, page, name, other)
    finally:
        with console.api() as api:  # the setting is the daemon's: leave it off for the next tests
            api.put("/api/competition", json={"on": False}).raise_for_status()


def _competition_mode_locks_uploads(console, page_for, page, name, other):
    page.check("[data-testid=competition] input[type=checkbox]")  # beside the match timer, on the Dashboard
    page.get_by_role("button", name="Start match").click()
    timer = page.locator("[data-testid=match-timer]")
    first = timer.inner_text()
    # It ticks once a second; on a loaded machine a tick can come late, so wait for one (up to 5 s).
    page.wait_for_function(
        "(f) => document.querySelector('[data-testid=match-timer]').innerText !== f", arg=first, timeout=5000
    )
    # The mode and its timer are the daemon's: a judge's page (a viewer) shows the same clock.
    with console.api() as api:
        assert api.get("/api/competition").json()["on"] is True
    judge = page_for(console.sign_in_url(console.mint("viewer")))
    judge.locator("[data-testid=match-timer]").wait_for()
    switch = "[data-testid=competition] input[type=checkbox]"
    assert judge.is_disabled(switch) and judge.is_checked(switch)
    mine, theirs = timer.inner_text(), judge.locator("[data-testid=match-timer]").inner_text()
    to_s = lambda clock: int(clock.split(":")[0]) * 60 + int(clock.split(":")[1])  # noqa: E731
    assert abs(to_s(mine) - to_s(theirs)) <= 1, (mine, theirs)

    open_program(page, "forever.py", FOREVER)
    page.keyboard.press("Control+s")  # saved through the daemon
    page.locator(".foot", has_text="Stored by the daemon").wait_for()
    page.locator("label.target", has_text=name).locator("input").check()
    page.keyboard.press("F5")  # run
    page.goto(page.url.split("#")[0] + "#/dashboard")
    tile = page.locator(f"[data-testid=hub-tile][data-hub='{name}']")
    tile.locator("[data-testid=hub-status]", has_text="running").wait_for()
    # While it runs, nothing can be uploaded or started, and the reason is on screen.
    page.goto(page.url.split("#")[0] + "#/editor")
    page.locator("[data-testid=readonly-reason]", has_text="Competition mode").wait_for()
    assert page.is_disabled("[data-testid=run]")
    assert "Competition mode" in (page.get_attribute("[data-testid=run]", "title") or "")
    screenshot(page, "editor-competition-locked")
    # Flashing and servo re-ID wait too (scanning, which changes nothing, does not).
    for route, button in (("flash", "Flash selected"), ("servo", "Change id")):
        page.goto(page.url.split("#")[0] + f"#/{route}")
        page.locator("[data-testid=readonly-reason]", has_text="Competition mode").wait_for()
        locked = page.get_by_role("button", name=button)
        assert locked.is_disabled() and "Competition mode" in (locked.get_attribute("title") or ""), route
    # What the page greys out, the daemon refuses: a script cannot upload to the other hub either.
    with console.api() as api:
        refused = api.post(f"/api/hubs/{other}/upload", json={"program": "forever.py"})
    assert refused.status_code == 409 and refused.json()["error"] == "competition_locked"
    assert f"{name} is running" in refused.json()["message"]
    page.keyboard.press("F6")  # stop the selected hub
    page.goto(page.url.split("#")[0] + "#/dashboard")
    tile.locator("[data-testid=hub-status]", has_text="idle").wait_for(timeout=15000)
    page.goto(page.url.split("#")[0] + "#/editor")
    page.locator("button.prog", has_text="forever.py").click()
    page.wait_for_function("() => !document.querySelector('[data-testid=run]').disabled")


def test_identify_from_a_tile_is_in_the_audit_log(console, page_for):
    page = page_for(console.url)
    hub = console.wait_hubs_idle(2)[0]
    page.locator(f"[data-testid=hub-tile][data-hub='{hub['name']}']").get_by_role(
        "button", name="Identify"
    ).click()
    page.goto(page.url.split("#")[0] + "#/audit")
    row = page.locator("[data-testid=audit] tr", has_text=f"Identified {hub['name']}")
    row.first.wait_for()
    assert "done" in row.first.inner_text()
    screenshot(page, "audit")
