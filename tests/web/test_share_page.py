"""The Share page in Debian's Chromium against a real `openbricks console` on 127.0.0.1: it says plainly
that the console listens on this computer only and how to start it for the room; an operator mints a
viewer link there (with its QR code), the link opens the console read-only in a second browser, a
viewer cannot mint one, and revoking the link shuts it out."""

from __future__ import annotations

import httpx
import pytest

from tests.web.conftest import screenshot

pytestmark = pytest.mark.e2e


def test_a_viewer_link_minted_on_the_page_opens_read_only_until_revoked(console, page_for):
    page = page_for(console.url)
    page.goto(f"{console.base}/#/share")
    local = page.locator("[data-testid=share-local-only]")
    local.wait_for()
    assert "this computer only" in local.inner_text()
    assert "--host 0.0.0.0 --allow-host" in local.inner_text()

    page.get_by_label("Role").select_option("viewer")
    page.get_by_label("Name").fill("mentor-ana")
    page.get_by_role("button", name="Make link").click()
    shown = page.locator("[data-testid=share-link]")
    shown.locator(".qr svg").wait_for()  # the QR code for a phone
    link = shown.get_by_label("Link", exact=True).input_value()
    assert link.startswith(f"{console.base}/?token=")
    page.locator("[data-testid=share-token][data-label=mentor-ana]").wait_for()
    screenshot(page, "share")
    token = link.split("token=", 1)[1]

    # The link in another browser: signed in as the mentor, read-only.
    mentor = page_for(link)
    mentor.locator("[data-testid=readonly-reason]").wait_for()
    assert "read-only" in mentor.locator("[data-testid=readonly-reason]").inner_text()
    me = mentor.evaluate("fetch('/api/auth/me').then((r) => r.json())")
    assert (me["label"], me["role"]) == ("mentor-ana", "viewer")
    mentor.goto(f"{console.base}/#/share")
    assert mentor.get_by_role("button", name="Make link").is_disabled()
    with httpx.Client(base_url=console.base, headers={"Authorization": f"Bearer {token}"}) as as_mentor:
        refused = as_mentor.post("/api/auth/tokens", json={"role": "operator"})
        assert refused.status_code == 403, refused.text

        page.locator("[data-testid=share-token][data-label=mentor-ana]").get_by_role(
            "button", name="Revoke"
        ).click()
        page.locator("[data-testid=share-token][data-label=mentor-ana]").wait_for(state="detached")
        assert as_mentor.get("/api/auth/me").status_code == 401
    assert page.errors == [] and mentor.errors == [], (page.errors, mentor.errors)
