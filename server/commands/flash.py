"""`openbricks flash`: write a firmware image over USB, then name the hub and record the image's provenance.

Steps, each announced on stderr: find the port, read the firmware already on the hub (version and
provenance, through its raw REPL), probe the chip with esptool, pick the image (the given file or the
newest release for that chip) and check it is built for this chip, verify its signature, ask before
writing the same or an older version, erase, write (with a progress bar), wait for the reboot, write the
hub name to NVS and read it back, store the provenance verdict, optionally the starter QTR calibration,
then reset so the hub advertises its new name.
"""

from __future__ import annotations

import asyncio
from pathlib import Path

from openbricks_server.console import ProgressBar, Steps, confirm
from openbricks_server.errors import EXIT_OK, CliError, UsageError
from openbricks_server.flash.esptool_runner import Esptool, chip_name
from openbricks_server.flash.image import FirmwareImage, ImageError, inspect_image, parse_version
from openbricks_server.flash.ports import find_esp_port, missing_port
from openbricks_server.flash.signing import public_key_path, signature_path, verify_file
from openbricks_server.hub_lock import hub_lock

MAX_NAME_BYTES = 26  # what fits in a legacy BLE advertisement next to the flags
RECOMMENDED_NAME_CHARS = 20
QTR_STARTER = Path(__file__).resolve().parent.parent / "flash" / "qtr_starter.json"
QTR_PATH = "/qtr.cal"


def validate_hub_name(name: str) -> str:
    stripped = name.strip()
    if not stripped:
        raise UsageError("--name is empty: give the hub a name you will use with `-n`, e.g. --name RobotA")
    if stripped != name:
        raise UsageError(
            f"--name {name!r} starts or ends with spaces; hubs are found by exact name, so drop them"
        )
    if any(not ch.isprintable() for ch in name):
        raise UsageError(f"--name {name!r} contains control characters; use letters, digits, - or _")
    if len(name.encode("utf-8")) > MAX_NAME_BYTES:
        raise UsageError(
            f"--name {name!r} is {len(name.encode('utf-8'))} bytes; a Bluetooth advertisement carries "
            f"at most {MAX_NAME_BYTES}: pick a shorter name"
        )
    return name


def main(args) -> int:
    name = validate_hub_name(args.name)
    # A given image is checked before any port is opened: a typo in the path is known at once.
    given = inspect_image(args.firmware) if args.firmware else None
    steps = Steps(args.verbose)
    if len(name) > RECOMMENDED_NAME_CHARS:
        steps.note(
            f"note: names of {RECOMMENDED_NAME_CHARS} characters or fewer show in full in every scanner"
        )
    problem = missing_port(args.port) if args.port else None
    if problem:
        raise CliError(f"--port {args.port}: {problem}")
    port = args.port or find_esp_port()
    steps.step(f"port {port}" + ("" if args.port else " (the only ESP device connected)"))
    with hub_lock(name):
        return _flash(args, name, port, steps, given)


def _flash(args, name: str, port: str, steps: Steps, given: FirmwareImage | None) -> int:
    from openbricks_server import hub_session

    steps.step("firmware on the hub")
    current = asyncio.run(hub_session.read_serial_info(port))
    if current is None:
        steps.note("no openbricks firmware answered (a blank chip, or other firmware)")
    else:
        steps.note(f"firmware {current.firmware}")

    tool = Esptool(port, echo=steps.note if args.verbose else None)
    steps.step("probe the chip")
    chip = tool.probe_chip()
    steps.note(f"chip {chip}")
    if args.chip != "auto" and chip_name(args.chip) != chip:
        raise CliError(
            f"--chip {args.chip} was given, but the board on {port} is an {chip}: drop --chip or fix it"
        )

    image, release_note = (given, "") if given is not None else _newest_release(chip, steps)
    if image.chip != chip:
        raise ImageError(
            f"{image.path.name} is built for {image.chip} but the board on {port} is an {chip}: flashing "
            f"it would leave a hub that cannot boot; use an {chip} image"
        )
    verdict = verify_file(image.path)
    steps.step(
        f"image {image.path.name}: {image.chip}, version {image.version or 'unknown'}, "
        f"written at {image.offset_hex} ({verdict.provenance}: {verdict.reason})"
    )
    if release_note:
        steps.note(release_note)
    steps.detail(f"image path {image.path}")
    steps.detail(f"signature {signature_path(image.path)}; public key {public_key_path()}")
    _confirm_version(current, image, args.yes)

    if args.skip_erase:
        steps.step("erase skipped (--skip-erase): keys already in NVS stay")
    else:
        steps.step("erase the flash")
        tool.erase(chip)
    steps.step("write the firmware")
    bar = ProgressBar("writing")
    tool.write(chip, args.baud, image.offset, str(image.path), bar.update)
    bar.finish()

    steps.step("wait for the hub to boot")
    qtr = QTR_STARTER.read_bytes() if args.with_qtr_init else None
    result = asyncio.run(hub_session.set_up_flashed_hub(port, name, verdict.provenance, qtr))
    steps.step(f"hub name {result['hub_name']!r} written and read back")
    steps.step(f"provenance recorded: firmware {result['firmware']}")
    if qtr is not None:
        steps.step(f"starter QTR calibration stored at {QTR_PATH} (calibrate on your own mat for real runs)")
    steps.step(f"reboot: the hub now advertises as {name!r}; try `openbricks run -n {name} main.py`")
    return EXIT_OK


def _newest_release(chip: str, steps: Steps) -> tuple[FirmwareImage, str]:
    from openbricks_server.flash.releases import newest_release, releases_url

    steps.step(f"newest release for {chip}")
    steps.detail(f"release index {releases_url()}")
    release = newest_release(chip, steps.note)
    steps.note(f"version {release.version} ({'downloaded' if release.downloaded else 'cached'})")
    steps.detail(f"cache {release.image}")
    image = inspect_image(release.image)
    if image.version is None:
        image = FirmwareImage(
            image.path, image.chip, image.offset, image.partition_table, image.size, release.version
        )
    return image, release.note


def _confirm_version(current, image: FirmwareImage, assume_yes: bool) -> None:
    if current is None or not image.version or not current.version:
        return
    have, want = parse_version(current.version), parse_version(image.version)
    if want > have:
        return
    relation = "the same version as" if want == have else "older than"
    confirm(
        f"{image.version} is {relation} the firmware on the hub ({current.firmware}). Flash it anyway?",
        assume_yes,
        "pass --yes to flash it anyway",
    )
