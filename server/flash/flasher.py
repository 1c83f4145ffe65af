"""Flashing one hub over USB: the one implementation behind `openbricks flash` and the console's flash jobs.

Steps, each reported to a `Reporter` (the CLI prints them on stderr; the daemon turns them into job
events): read the firmware already on the hub (version and provenance, through its raw REPL), probe the
chip with esptool, pick the image (the given file, or the newest release for that chip from the releases
the caller found before opening the port) and check it is built for this chip, verify its signature,
refuse the same or an older version unless the caller allows it (the CLI asks; the daemon takes
`allow_downgrade`), erase, write (with progress), wait for the reboot, write the hub name to NVS and read
it back, store the provenance verdict, optionally the starter QTR calibration, then reset so the hub
advertises its new name.

The hub's lock (`hub_lock(name)`) is held throughout, so no other openbricks command talks to it meanwhile.
"""

from __future__ import annotations

import asyncio
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Protocol

from openbricks_server.errors import CliError, UsageError
from openbricks_server.flash.esptool_runner import Esptool, chip_name
from openbricks_server.flash.image import FirmwareImage, ImageError, inspect_image, parse_version
from openbricks_server.flash.releases import MANIFEST_NAME, Releases, find_releases, newest_release
from openbricks_server.flash.signing import public_key_path, signature_path, verify_file

MAX_NAME_BYTES = 26  # what fits in a legacy BLE advertisement next to the flags
RECOMMENDED_NAME_CHARS = 20
DEFAULT_BAUD = 460800
QTR_STARTER = Path(__file__).resolve().parent / "qtr_starter.json"
QTR_PATH = "/qtr.cal"


class FlashRefused(CliError):
    """A safety gate stopped the flash before anything was written."""


class Reporter(Protocol):
    def step(self, text: str) -> None:
        """A step begins (one line a user reads)."""

    def note(self, text: str) -> None:
        """More about the current step."""

    def detail(self, text: str) -> None:
        """Paths and command lines: shown with --verbose, kept in a job's log."""

    def progress(self, percent: float) -> None:
        """Write progress, 0..100; called with 100 once the write is done."""


@dataclass(frozen=True)
class FlashRequest:
    port: str
    name: str
    image: FirmwareImage | None = None  # None: the newest release for the detected chip, from `releases`
    releases: Releases | None = None  # found by the caller before opening the port (None: looked up here)
    chip: str = "auto"  # what the caller expects ("auto": whatever esptool finds)
    baud: int = DEFAULT_BAUD
    skip_erase: bool = False
    with_qtr_init: bool = False


@dataclass(frozen=True)
class FlashResult:
    port: str
    hub_name: str
    chip: str
    image: str
    version: str | None
    provenance: str  # official / customized, the signature verdict
    firmware: str  # the label the flashed hub reports
    previous_firmware: str | None  # what the hub ran before (None: a blank chip or other firmware)


def validate_hub_name(name: str, option: str = "--name") -> str:
    """`name` if a hub can advertise it; UsageError saying why not otherwise."""
    stripped = name.strip()
    if not stripped:
        raise UsageError(f"{option} is empty: give the hub a name you will use with `-n`, e.g. RobotA")
    if stripped != name:
        raise UsageError(
            f"{option} {name!r} starts or ends with spaces; hubs are found by exact name, so drop them"
        )
    if any(not ch.isprintable() for ch in name):
        raise UsageError(f"{option} {name!r} contains control characters; use letters, digits, - or _")
    if len(name.encode("utf-8")) > MAX_NAME_BYTES:
        raise UsageError(
            f"{option} {name!r} is {len(name.encode('utf-8'))} bytes; a Bluetooth advertisement carries "
            f"at most {MAX_NAME_BYTES}: pick a shorter name"
        )
    return name


def older_version_refusal(hint: str) -> Callable[[str], None]:
    """A `confirm_older` that refuses: for callers that cannot ask (the daemon, a script)."""

    def refuse(question: str) -> None:
        raise FlashRefused(f"{question.removesuffix(' Flash it anyway?')}: not flashed; {hint}")

    return refuse


async def flash_hub(
    request: FlashRequest,
    report: Reporter,
    confirm_older: Callable[[str], None],
    echo: Callable[[str], None] | None = None,
) -> FlashResult:
    """Flash the hub on `request.port` and name it; `confirm_older(question)` returns to go on with the
    same or an older version than the hub runs, or raises. `echo` receives esptool command lines."""
    from openbricks_server.hub_lock import hub_lock

    with hub_lock(request.name):
        return await _flash(request, report, confirm_older, echo)


async def _flash(request, report: Reporter, confirm_older, echo) -> FlashResult:
    from openbricks_server import hub_session

    port = request.port
    report.step("firmware on the hub")
    current = await hub_session.read_serial_info(port)
    if current is None:
        report.note("no openbricks firmware answered (a blank chip, or other firmware)")
    else:
        report.note(f"firmware {current.firmware}")

    tool = Esptool(port, echo=echo)
    report.step("probe the chip")
    chip = await tool.probe_chip()
    report.note(f"chip {chip}")
    if request.chip != "auto" and chip_name(request.chip) != chip:
        raise FlashRefused(
            f"--chip {request.chip} was given, but the board on {port} is an {chip}: drop --chip or fix it"
        )

    image, release_note = (
        (request.image, "")
        if request.image is not None
        else await _newest_release(chip, request.releases, report)
    )
    if image.chip != chip:
        raise ImageError(
            f"{image.path.name} is built for {image.chip} but the board on {port} is an {chip}: flashing "
            f"it would leave a hub that cannot boot; use an {chip} image"
        )
    verdict = await asyncio.to_thread(verify_file, image.path)
    report.step(
        f"image {image.path.name}: {image.chip}, version {image.version or 'unknown'}, "
        f"written at {image.offset_hex} ({verdict.provenance}: {verdict.reason})"
    )
    if release_note:
        report.note(release_note)
    report.detail(f"image path {image.path}")
    report.detail(f"signature {signature_path(image.path)}; public key {public_key_path()}")
    _check_version(current, image, confirm_older)

    if request.skip_erase:
        report.step("erase skipped: keys already in NVS stay")
    else:
        report.step("erase the flash")
        await tool.erase(chip)
    report.step("write the firmware")
    await tool.write(chip, request.baud, image.offset, str(image.path), report.progress)

    report.step("wait for the hub to boot")
    qtr = QTR_STARTER.read_bytes() if request.with_qtr_init else None
    done = await hub_session.set_up_flashed_hub(port, request.name, verdict.provenance, qtr)
    report.step(f"hub name {done['hub_name']!r} written and read back")
    report.step(f"provenance recorded: firmware {done['firmware']}")
    if qtr is not None:
        report.step(f"starter QTR calibration stored at {QTR_PATH} (calibrate on your own mat for real runs)")
    return FlashResult(
        port=port,
        hub_name=done["hub_name"],
        chip=chip,
        image=str(image.path),
        version=image.version,
        provenance=verdict.provenance,
        firmware=done["firmware"],
        previous_firmware=current.firmware if current is not None else None,
    )


async def _newest_release(
    chip: str, releases: Releases | None, report: Reporter
) -> tuple[FirmwareImage, str]:
    if releases is None:
        releases = await asyncio.to_thread(find_releases, chip)
    if releases.url is None:
        report.step(f"cached release for {chip}")
    else:
        report.step(f"newest release for {chip}")
        report.detail(f"release index {releases.url}/{MANIFEST_NAME}")
    release = await asyncio.to_thread(newest_release, chip, releases, report.note)
    report.note(f"version {release.version} ({'downloaded' if release.downloaded else 'cached'})")
    report.detail(f"cache {release.image}")
    image = inspect_image(release.image)
    if image.version is None:
        image = FirmwareImage(
            image.path, image.chip, image.offset, image.partition_table, image.size, release.version
        )
    return image, release.note


def _check_version(current, image: FirmwareImage, confirm_older: Callable[[str], None]) -> None:
    if current is None or not image.version or not current.version:
        return
    have, want = parse_version(current.version), parse_version(image.version)
    if want > have:
        return
    relation = "the same version as" if want == have else "older than"
    confirm_older(
        f"{image.version} is {relation} the firmware on the hub ({current.firmware}). Flash it anyway?"
    )
