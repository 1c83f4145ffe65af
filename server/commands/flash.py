"""`openbricks flash`: write a firmware image over USB, then name the hub and record the image's provenance.

The steps are `openbricks_server.flash.flasher`'s (shared with the console's flash jobs); this front end
finds the port, prints each step on stderr with a progress bar, and asks before writing the same or an
older version (`--yes` answers for a script).
"""

from __future__ import annotations

import asyncio

from openbricks_server import console_client
from openbricks_server.console import ProgressBar, Steps, confirm
from openbricks_server.errors import EXIT_OK, CliError
from openbricks_server.flash.flasher import (
    RECOMMENDED_NAME_CHARS,
    FlashRequest,
    flash_hub,
    validate_hub_name,
)
from openbricks_server.flash.image import inspect_image
from openbricks_server.flash.ports import find_esp_port, missing_port
from openbricks_server.flash.releases import find_releases


class _TerminalReport:
    """The flasher's steps as `==> step` lines, and the write as a progress bar."""

    def __init__(self, steps: Steps):
        self.steps = steps
        self.step, self.note, self.detail = steps.step, steps.note, steps.detail
        self._bar: ProgressBar | None = None

    def progress(self, percent: float) -> None:
        if self._bar is None:
            self._bar = ProgressBar("writing")
        self._bar.update(percent)
        if percent >= 100:
            self._bar.finish()


def main(args) -> int:
    name = validate_hub_name(args.name)
    # A given image is checked before any port is opened: a typo in the path is known at once.
    given = inspect_image(args.firmware) if args.firmware else None
    problem = missing_port(args.port) if args.port else None
    if problem:
        raise CliError(f"--port {args.port}: {problem}")
    # Without an image, what can be flashed is known before any port is opened: with no release reachable
    # and none cached, the command stops here, in a moment, saying how to build an image.
    releases = None if given else find_releases(None if args.chip == "auto" else args.chip)
    steps = Steps(args.verbose)
    if len(name) > RECOMMENDED_NAME_CHARS:
        steps.note(
            f"note: names of {RECOMMENDED_NAME_CHARS} characters or fewer show in full in every scanner"
        )
    port = args.port or find_esp_port()
    console_client.refuse_held_port(port, "flash it from the console (its Flash page, or POST /api/flash)")
    steps.step(f"port {port}" + ("" if args.port else " (the only ESP device connected)"))
    request = FlashRequest(
        port=port,
        name=name,
        image=given,
        releases=releases,
        chip=args.chip,
        baud=args.baud,
        skip_erase=args.skip_erase,
        with_qtr_init=args.with_qtr_init,
    )

    def confirm_older(question: str) -> None:
        confirm(question, args.yes, "pass --yes to flash it anyway")

    asyncio.run(
        flash_hub(request, _TerminalReport(steps), confirm_older, echo=steps.note if args.verbose else None)
    )
    steps.step(f"reboot: the hub now advertises as {name!r}; try `openbricks run -n {name} main.py`")
    return EXIT_OK
