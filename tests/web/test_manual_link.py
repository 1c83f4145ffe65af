"""The Manual link in the console's navigation opens the documentation the daemon serves from the
package (/manual/), signed in with the console's own cookie, and its pages link on to each other."""

import pytest

pytestmark = pytest.mark.e2e


def test_the_manual_link_opens_the_packaged_site_in_a_new_tab(console, page_for):
    page = page_for(console.sign_in_url(console.token))
    link = page.locator("[data-testid=manual-link]")
    assert link.get_attribute("href") == "/manual/"
    with page.context.expect_page() as opened:
        link.click()
    manual = opened.value
    manual.wait_for_load_state()
    assert manual.url == f"{console.base}/manual/"
    assert manual.locator("h1").first.inner_text().startswith("openbricks")
    manual.get_by_role("link", name="API reference").first.click()
    manual.get_by_role("link", name="robotics: DriveBase").first.click()
    manual.wait_for_load_state()
    assert manual.url.endswith("/manual/api/drivebase.html")
    assert manual.locator("[id='openbricks.robotics.drivebase.DriveBase.straight']").count() == 1
    assert page.errors == [] and manual.title().startswith("robotics: DriveBase")
