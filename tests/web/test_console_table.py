"""The console at the competition table: a STOP ALL that is on screen on a phone and never pressed by
accident, a page that says so when the console is gone (and comes back by itself), and words a student
understands. Real console, two virtual hubs, Debian's Chromium; screenshots of every page at laptop and
phone width are kept in build/artifacts/web/."""

from __future__ import annotations

import os
import re
import signal
import time

import httpx
import pytest

from tests.web.conftest import screenshot
from tests.web.console_process import start_console, stop_console

pytestmark = pytest.mark.e2e

FOREVER = """from openbricks.tools import wait

i = 0
while True:
    print("table", i)
    i += 1
    wait(100)
"""

PHONES = [(390, 844), (360, 740)]


def hub_statuses(console) -> dict[str, str]:
    with console.api() as c:
        return {h["name"]: h["status"] for h in c.get("/api/hubs").json()["hubs"]}


def run_forever_on_both(console) -> list[str]:
    hubs = [h["name"] for h in console.wait_hubs_idle(2)]
    with console.api() as c:
        c.put("/api/programs/table_forever.py", json={"source": FOREVER}).raise_for_status()
        for name in hubs:
            console.run(c, name, "table_forever.py")
    wait_until(lambda: all(hub_statuses(console)[n] == "running" for n in hubs), "both hubs running")
    return hubs


def wait_until(predicate, what: str, timeout_s: float = 20) -> None:
    deadline = time.monotonic() + timeout_s
    while time.monotonic() < deadline:
        if predicate():
            return
        time.sleep(0.1)
    raise AssertionError(f"not within {timeout_s} s: {what}")


def answers(base: str) -> bool:
    try:
        return httpx.get(f"{base}/", timeout=2).status_code < 500
    except httpx.HTTPError:
        return False


def no_sideways_scroll(page, where: str) -> None:
    overflow = page.evaluate("() => document.documentElement.scrollWidth - window.innerWidth")
    assert overflow <= 1, f"{where} is {overflow}px wider than the window"


def test_stop_all_is_on_screen_on_a_phone_and_stops_both_hubs(console, page_for):
    hubs = run_forever_on_both(console)
    page = page_for(console.url, 360, 740)
    for phone in PHONES:
        page.set_viewport_size({"width": phone[0], "height": phone[1]})
        for where in ("dashboard", "output"):
            page.goto(f"{console.base}/#/{where}")
            page.locator("main h1").first.wait_for()
            page.wait_for_timeout(200)
            no_sideways_scroll(page, f"{where} at {phone[0]}x{phone[1]}")
            box = page.locator("[data-testid=stop-all]").bounding_box()
            assert box and box["x"] >= 0 and box["y"] >= 0, box
            assert box["x"] + box["width"] <= phone[0] and box["y"] + box["height"] <= phone[1], (phone, box)
    page.goto(f"{console.base}/#/dashboard")
    page.click("[data-testid=stop-all]")
    wait_until(lambda: all(hub_statuses(console)[n] == "idle" for n in hubs), "both hubs stopped")
    page.locator("[data-testid=notice]", has_text="Stopped").first.wait_for()
    screenshot(page, "dashboard-stopped-360x740")
    # Again, with nothing running: a quiet success, not a red "not stopped".
    page.click("[data-testid=stop-all]")
    page.locator("[data-testid=notice]", has_text="nothing was running").wait_for()
    assert page.locator(".notice.error").count() == 0


def test_esc_in_the_editor_stops_nothing_and_the_chord_does(console, page_for):
    hubs = run_forever_on_both(console)
    page = page_for(console.sign_in_url(console.token, "editor"))
    assert "Ctrl+." in (page.get_attribute("[data-testid=stop-all]", "title") or "")
    page.locator("button.prog", has_text="table_forever.py").click()
    page.locator(".cm-content").click()
    page.keyboard.press("Escape")  # closing a completion or search box: never STOP ALL
    page.keyboard.press("Escape")
    page.wait_for_timeout(800)
    assert all(hub_statuses(console)[n] == "running" for n in hubs), hub_statuses(console)
    page.keyboard.press("Control+.")  # the documented chord stops all from inside the editor
    wait_until(lambda: all(hub_statuses(console)[n] == "idle" for n in hubs), "the chord stopped both hubs")


def test_words_a_student_understands(console, page_for):
    hubs = run_forever_on_both(console)
    page = page_for(console.url)
    assert page.inner_text("[data-testid=bluetooth]") == "Bluetooth: off"  # started with --no-ble
    tile = page.locator(f"[data-testid=hub-tile][data-hub='{hubs[0]}']")
    tile.locator("[data-testid=hub-status]", has_text="running").wait_for()
    # A refused action says why, beside the button clicked, in plain words.
    identify = tile.get_by_role("button", name="Identify")
    identify.click()
    notice = page.locator(".notice.here", has_text="is busy")
    notice.wait_for()
    said = notice.inner_text()
    assert "POST" not in said and "/api/" not in said and not re.search(r"\d{4}-\d\d-\d\dT", said), said
    box, near = notice.bounding_box(), identify.bounding_box()
    assert box and near and abs(box["y"] - (near["y"] + near["height"])) < 140, (box, near)
    screenshot(page, "dashboard-refused-here")
    page.click("[data-testid=stop-all]")
    tile.locator("[data-testid=hub-status]", has_text="idle").wait_for(timeout=15000)
    tile.locator("[data-testid=last-outcome]", has_text="stopped").wait_for()
    # Identify shows that it happened.
    identify.click()
    tile.locator("[data-testid=identify-done]").wait_for()
    # The stopped run's end reads once ("stopped", never "stopped: stopped").
    page.goto(f"{console.base}/#/output")
    page.locator("[data-testid=terminal]", has_text="■ stopped").first.wait_for()
    assert "stopped: stopped" not in page.inner_text("main")
    # Notices do not follow the user to the next page.
    page.goto(f"{console.base}/#/audit")
    page.locator("[data-testid=audit] td", has_text="Stopped all hubs").first.wait_for()
    assert page.locator("[data-testid=notice]").count() == 0
    table = page.inner_text("[data-testid=audit]")
    assert f"Identified {hubs[0]}" in table and "/api/" not in table and "POST" not in table, table
    assert f"Ran table_forever.py on {hubs[0]}" in table, table
    assert "Competition mode" not in page.inner_text("main")  # it lives on the Dashboard now
    page.goto(f"{console.base}/#/dashboard")
    page.locator("[data-testid=competition]", has_text="Competition mode").wait_for()
    # A bad link opened in a browser is a page to read, not JSON.
    page.goto(f"{console.base}/?token=expired-link")
    assert "not valid" in page.inner_text("body") and '"error"' not in page.content()


def test_a_lost_console_greys_the_page_and_it_comes_back_by_itself(tmp_path, page_for):
    console = start_console(tmp_path)
    try:
        console.wait_hubs_idle(2)
        operator = console.mint("operator")  # kept in the store: the cookie outlives a restart
        page = page_for(console.sign_in_url(operator))
        # A second page signed in with the printed token, which a restart replaces.
        printed = page_for(console.url)
        page.locator("[data-testid=hub-tile]").nth(1).wait_for()
        page.wait_for_function("() => !document.querySelector('[data-testid=stop-all]').disabled")
        os.killpg(console.process.pid, signal.SIGKILL)
        killed = time.monotonic()
        page.locator("[data-testid=connection-lost]").wait_for(timeout=2000)
        stop_all_off = "() => document.querySelector('[data-testid=stop-all]').disabled"
        page.wait_for_function(stop_all_off, timeout=2000)
        assert time.monotonic() - killed < 2.0
        assert page.locator("[data-testid=last-known]").count() == 2
        for button in page.locator("[data-testid=hub-tile] footer button").all():
            assert button.is_disabled(), button.inner_text()
        assert "not reachable" in (page.get_attribute("[data-testid=stop-all]", "title") or "")
        screenshot(page, "dashboard-console-lost")
        console.process.wait(timeout=10)

        port = int(console.base.rsplit(":", 1)[1])
        console = start_console(tmp_path, port=port)
        wait_until(lambda: answers(console.base), "the console answers again")
        back = time.monotonic()
        page.locator("[data-testid=connection-lost]").wait_for(state="detached", timeout=3000)
        page.wait_for_function(f"() => !({stop_all_off})()", timeout=3000)
        assert time.monotonic() - back < 2.5
        assert page.locator("[data-testid=last-known]").count() == 0
        # The page signed in with the old printed token says so, instead of retrying for ever.
        printed.locator("[data-testid=connection-lost]", has_text="Signed out").wait_for(timeout=5000)
        assert printed.is_disabled("[data-testid=stop-all]")
        screenshot(printed, "dashboard-signed-out")
    finally:
        stop_console(console.process)


SCREENS = ["dashboard", "editor", "output", "history", "telemetry", "sim", "flash", "servo", "audit", "share"]


def test_every_page_is_kept_as_a_screenshot_at_laptop_and_phone_width(console, page_for):
    page = page_for(console.url, 1440, 900)
    for width, height in ((1440, 900), (390, 844)):
        page.set_viewport_size({"width": width, "height": height})
        for page_id in SCREENS:
            page.goto(f"{console.base}/#/{page_id}")
            page.locator("main h1, main h3").first.wait_for()
            page.wait_for_timeout(250)
            box = page.locator("[data-testid=stop-all]").bounding_box()
            assert box and box["x"] + box["width"] <= width, (page_id, width, box)
            screenshot(page, f"page-{page_id}-{width}x{height}")
    assert page.errors == [], page.errors
