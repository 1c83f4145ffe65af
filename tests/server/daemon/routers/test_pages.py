"""The console's pages: the documentation site at /manual/, for whoever is signed in."""

import httpx


def test_a_signed_in_browser_reads_the_manual_and_the_api_page_stays_at_docs(daemon):
    with httpx.Client(base_url=daemon.url) as browser:
        browser.get(f"/?token={daemon.token}", follow_redirects=False)  # the printed URL: a cookie
        index = browser.get("/manual/")
        assert index.status_code == 200 and "api/index.html" in index.text
        page = browser.get("/manual/api/drivebase.html")
        assert page.status_code == 200
        assert 'id="openbricks.robotics.drivebase.DriveBase.straight"' in page.text
        style = browser.get("/manual/_static/pygments.css")
        assert style.status_code == 200 and style.headers["content-type"].startswith("text/css")
        assert "swagger" in browser.get("/docs").text.lower()  # the API's own page is untouched


def test_the_manual_needs_a_sign_in_like_every_page(daemon):
    refused = httpx.get(f"{daemon.url}/manual/")
    assert refused.status_code == 401 and refused.json()["error"] == "unauthorized"
