"""A real `openbricks console` (uvicorn on 127.0.0.1, two virtual hubs with the simulator behind them) and
Debian's Chromium driven by Playwright, for the browser console's end-to-end tests.

The daemon runs as the user starts it, in its own process; the browser signs in with the URL it prints,
exactly as a person would. Screenshots land in build/artifacts/web/ (kept after the run, gitignored).
"""

from __future__ import annotations

import io
import re
from pathlib import Path

import numpy as np
import pytest
from PIL import Image

from tests.web.console_process import start_console, stop_console

CHROMIUM = "/usr/bin/chromium"
ARTIFACTS = Path(__file__).resolve().parents[2] / "build" / "artifacts" / "web"


@pytest.fixture(scope="module")
def console(tmp_path_factory):
    c = start_console(tmp_path_factory.mktemp("console"))
    try:
        c.wait_hubs_idle(2)
        yield c
    finally:
        stop_console(c.process)


@pytest.fixture(scope="module")
def browser():
    from playwright.sync_api import sync_playwright

    assert Path(CHROMIUM).exists(), "Debian's chromium is needed: `make setup` installs it (APT_PACKAGES)"
    with sync_playwright() as p:
        b = p.chromium.launch(executable_path=CHROMIUM, args=["--disable-gpu"])
        try:
            yield b
        finally:
            b.close()


@pytest.fixture
def page_for(browser, request):
    """`page_for(url, width, height)`: a fresh signed-in browser context per call, closed after the test
    (when the test fails, each page's last state is kept as `failed-<test>-N.png` beside the screenshots)."""
    contexts = []

    def open_page(url: str, width: int = 1280, height: int = 800):
        context = browser.new_context(viewport={"width": width, "height": height})
        contexts.append(context)
        page = context.new_page()
        page.set_default_timeout(20000)
        errors: list[str] = []
        page.on("pageerror", lambda e: errors.append(str(e)))
        page.errors = errors  # type: ignore[attr-defined]
        page.goto(url)
        page.wait_for_selector("[data-testid=stop-all]")
        return page

    yield open_page
    report = getattr(request.node, "call_report", None)
    if report is not None and report.failed:
        ARTIFACTS.mkdir(parents=True, exist_ok=True)
        name = re.sub(r"[^A-Za-z0-9_.-]+", "-", request.node.name)
        for i, c in enumerate(contexts):
            for page in c.pages:
                page.screenshot(path=str(ARTIFACTS / f"failed-{name}-{i}.png"))
    for c in contexts:
        c.close()


@pytest.hookimpl(wrapper=True)
def pytest_runtest_makereport(item, call):
    """Keep the test's outcome on the item, so a page fixture can screenshot what a failed test saw."""
    report = yield
    if report.when == "call":
        item.call_report = report
    return report


def screenshot(page, name: str) -> Path:
    """Keep a screenshot as a test artefact and check it shows something: not one flat colour."""
    ARTIFACTS.mkdir(parents=True, exist_ok=True)
    path = ARTIFACTS / f"{name}.png"
    png = page.screenshot(path=str(path))
    pixels = np.asarray(Image.open(io.BytesIO(png)).convert("L"), dtype=np.float64)
    assert pixels.std() > 8, f"{name}: the screenshot is nearly blank (pixel std {pixels.std():.1f})"
    # Many distinct grey levels: text and controls, not a few filled boxes.
    assert len(np.unique(pixels.astype(np.uint8))) > 40, f"{name}: the screenshot shows too little"
    return path
