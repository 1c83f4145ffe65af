"""The Flash and Servo-ID pages in Debian's Chromium against a real `openbricks console`: a USB hub (a
virtual hub's pty given with --serial, the fake esptool standing in for the chip work) and an unplugged
port flashed at once from the page (after a flash with no image chosen and no release to take was refused
with how to build one), progress to 100 % and a result per port, both jobs in the History
page's Jobs (live, and after a reload); a servo re-ID through a virtual hub, read back; a viewer can
change neither."""

from __future__ import annotations

import time

import pytest

from tests.server.commands.conftest import board  # noqa: F401 - the fixture
from tests.server.flash.conftest import fake_esptool  # noqa: F401 - the fixture
from tests.server.flash.images import build_image
from tests.web.conftest import screenshot
from tests.web.console_process import start_console, stop_console

pytestmark = pytest.mark.e2e


@pytest.fixture
def usb_console(tmp_path, board, fake_esptool, monkeypatch):  # noqa: F811 - the fixture, used
    monkeypatch.setenv("FAKE_ESPTOOL_WRITE_S", "3")  # long enough to watch the bar move
    monkeypatch.setenv("OPENBRICKS_CACHE_DIR", str(tmp_path / "cache"))  # no release cached ...
    monkeypatch.delenv("OPENBRICKS_RELEASES_URL", raising=False)  # ... and none to fetch
    console = start_console(tmp_path / "console", virtual=1, extra=["--serial", board.pty])
    try:
        console.wait_hubs_idle(2)
        yield console
    finally:
        stop_console(console.process)


def hub_status(console, hub_id: str) -> str:
    with console.api() as api:
        return api.get(f"/api/hubs/{hub_id}").json()["status"]


def test_flash_two_ports_from_the_page_one_succeeds_one_fails_alone(
    usb_console,
    board,  # noqa: F811 - the fixture, used
    page_for,
    tmp_path,
):
    hub_id = "serial:" + board.pty.removeprefix("/dev/").replace("/", "-")
    image = tmp_path / "firmware.bin"
    image.write_bytes(build_image("esp32s3", version="2.8.0"))
    # A second page watches the history's jobs from before the flash: they must appear there live.
    watcher = page_for(usb_console.url)
    watcher.goto(f"{usb_console.base}/#/history?view=jobs")
    watcher.locator("[data-testid=jobs] .empty", has_text="No jobs match").wait_for()
    page = page_for(usb_console.url)
    page.goto(f"{usb_console.base}/#/flash")
    page.get_by_role("button", name="Scan ports").click()
    row = page.locator(f"[data-testid=flash-row][data-port='{board.pty}']")
    row.wait_for()
    assert row.locator("input[type=text]").input_value() == hub_id.removeprefix("serial:")  # its name now
    row.locator("input[type=text]").fill("RobotW")
    row.locator("input[type=checkbox]").check()
    page.fill("input[aria-label='Port to add']", "/dev/ttyUSB97")
    page.get_by_role("button", name="Add port").click()
    ghost = page.locator("[data-testid=flash-row][data-port='/dev/ttyUSB97']")
    assert page.get_by_role("button", name="Flash selected (2)").is_disabled()  # a name is missing
    ghost.locator("input[type=text]").fill("Ghost")
    assert "firmware/build_firmware.sh" in page.locator("[data-testid=firmware]").inner_text()
    page.get_by_role("button", name="Flash selected (2)").click()  # no image chosen, no release to take
    confirm = page.locator("[data-testid=flash-confirm]")
    assert "none chosen" in confirm.inner_text()  # it asks first, saying which image it would write
    confirm.get_by_role("button", name="Flash 2 hubs").click()
    refused = page.locator(".notice", has_text="no firmware image")
    refused.wait_for()
    assert "firmware/build_firmware.sh" in refused.inner_text()
    assert ghost.locator("[data-testid=flash-state]").count() == 0  # nothing started
    page.set_input_files("input[aria-label='Firmware image']", str(image))
    page.locator("[data-testid=firmware]", has_text="esp32s3, version 2.8.0, written at 0x0").wait_for()
    page.get_by_role("button", name="Flash selected (2)").click()
    # One confirmation before anything is written: the ports, the image, its version and the names.
    asked = confirm.inner_text()
    for shown in (board.pty, "/dev/ttyUSB97", "firmware.bin", "version 2.8.0", "RobotW", "Ghost"):
        assert shown in asked, (shown, asked)
    screenshot(page, "flash-confirm")
    confirm.get_by_role("button", name="Cancel").click()  # cancelled: nothing starts
    assert confirm.count() == 0 and ghost.locator("[data-testid=flash-state]").count() == 0
    page.get_by_role("button", name="Flash selected (2)").click()
    confirm.get_by_role("button", name="Flash 2 hubs").click()

    ghost.locator("[data-testid=flash-state]", has_text="failed").wait_for()
    assert "there is no such port" in ghost.locator("[data-testid=flash-message]").inner_text()
    deadline = time.monotonic() + 60
    while hub_status(usb_console, hub_id) != "flashing":  # the console let go of the hub's port
        assert time.monotonic() < deadline, "the USB hub never showed flashing"
        time.sleep(0.1)
    row.locator("[data-testid=flash-state]", has_text="running").wait_for()
    screenshot(page, "flash-running")
    row.locator("[data-testid=flash-state]", has_text="done").wait_for(timeout=120000)
    assert "100 %" in row.inner_text() and "named RobotW" in row.inner_text()
    assert board.nvs_blob("openbricks", "hub_name") == b"RobotW"
    screenshot(page, "flash-done")
    assert page.errors == [], page.errors

    # Both jobs are in the history with how each ended: on the watching page as they happened, and read
    # back from the store on a fresh visit, where one can be opened and the list filtered.
    for history in (watcher, page):
        if history is page:
            page.goto(f"{usb_console.base}/#/history")
            page.get_by_role("tab", name="Jobs").click()
        done = history.locator("[data-testid=job-row][data-state=done]", has_text=board.pty)
        done.wait_for()
        assert "Flash" in done.inner_text() and "named RobotW" in done.inner_text()
        failed = history.locator("[data-testid=job-row][data-state=failed]", has_text="/dev/ttyUSB97")
        failed.wait_for()
        assert "there is no such port" in failed.inner_text()
    failed.click()
    detail = page.locator("[data-testid=job-detail]")
    detail.locator("[data-testid=job-outcome]", has_text="there is no such port").wait_for()
    assert "Ghost" in detail.inner_text()  # what was asked: the name it was to get
    page.select_option("select[aria-label='Job state']", "failed")
    page.wait_for_function("() => document.querySelectorAll('[data-testid=job-row]').length === 1")
    screenshot(page, "history-jobs")
    assert watcher.errors == [] and page.errors == [], (watcher.errors, page.errors)

    # The audit log says how each flash ended, not that the request was taken.
    page.goto(f"{usb_console.base}/#/audit")
    audit = page.locator("[data-testid=audit] tr")
    audit.filter(has_text="Flash: /dev/ttyUSB97").filter(has_text="failed").wait_for()
    audit.filter(has_text=f"Flash: {board.pty}").filter(has_text="done").wait_for()
    results = audit.filter(has_text="Started flashing").locator("td:last-child").all_inner_texts()
    # The request that was taken reads started (it is not how the flashes ended); the one without an
    # image was refused.
    assert sorted(results) == ["refused (busy or locked)", "started"], results

    viewer = page_for(usb_console.sign_in_url(usb_console.mint("viewer"), "flash"))
    viewer.locator("[data-testid=readonly-reason]").wait_for()
    assert viewer.get_by_role("button", name="Flash selected (0)").is_disabled()


def test_re_id_a_servo_through_a_hub_from_the_page(usb_console, page_for):
    page = page_for(usb_console.url)
    page.goto(f"{usb_console.base}/#/servo")
    page.select_option("select[aria-label=Hub]", label="SimHub-1")
    page.get_by_role("button", name="Scan bus").click()
    result = page.locator("[data-testid=servo-result]")
    result.filter(has_text="servo ids on SimHub-1's servo bus: 1, 2").wait_for(timeout=90000)
    page.locator("[data-testid=servo-id]", has_text="2").click()
    page.fill("input[aria-label='New id']", "7")
    page.get_by_role("button", name="Change id").click()
    result.filter(has_text="servo 2 is now id 7 (read back from the servo); ids on the bus: 1, 7").wait_for(
        timeout=90000
    )
    screenshot(page, "servo-reid")
    page.fill("input[aria-label='New id']", "1")  # taken: refused with the CLI's words, nothing changed
    page.get_by_role("button", name="Change id").click()
    page.locator(".notice", has_text="id 1 is already taken").first.wait_for(timeout=90000)
    assert page.errors == [], page.errors

    viewer = page_for(usb_console.sign_in_url(usb_console.mint("viewer"), "servo"))
    viewer.locator("[data-testid=readonly-reason]").wait_for()
    assert viewer.get_by_role("button", name="Change id").is_disabled()
