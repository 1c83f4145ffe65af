"""Released firmware images for `openbricks flash` without `--firmware`: where they come from, and the cache.

openbricks has published no firmware release yet, so there is no releases location by default
(`DEFAULT_RELEASES_URL` is None until this project publishes its own): nothing is fetched unless
OPENBRICKS_RELEASES_URL names a location (an http(s) or file URL, e.g. a fork's or a team's own
mirror). Without one, only an image cached earlier can be used, and with neither, the command stops
before any port is opened with one line that says how to build an image and pass it with --firmware,
rather than probing a board for an image that cannot come.

A releases location serves `latest.json`:

    {"version": "2.7.1",
     "images": {"esp32s3": "openbricks-esp32s3-firmware-2.7.1.bin",
                "esp32": "openbricks-esp32-firmware-2.7.1.bin"}}

and, beside it, each image and its `.sig`. Files land in `<cache>/firmware/<version>/`; an image already
there is not fetched again. The index is asked with a short timeout, so an unreachable location costs
seconds at most; then the newest cached image for the chip is used, and the output says so.
"""

from __future__ import annotations

import json
import os
import urllib.error
import urllib.request
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

from openbricks_server.errors import CliError
from openbricks_server.flash.image import parse_version, release_chip
from openbricks_server.flash.signing import SIGNATURE_SUFFIX
from openbricks_server.paths import firmware_cache_dir

RELEASES_URL_ENV = "OPENBRICKS_RELEASES_URL"
# This project's own releases location once it publishes images; None until then, so that no default
# sends anyone to another project's releases or promises a download that cannot happen. Setting it makes
# `openbricks flash --help` (server/cli.py) and docs/firmware.md's "Releases" untrue: change them with it.
DEFAULT_RELEASES_URL: str | None = None
MANIFEST_NAME = "latest.json"
INDEX_TIMEOUT_S = 3  # the index is a few hundred bytes: a location this slow to answer is unreachable
IMAGE_TIMEOUT_S = 30  # per read of an image of a few MB
BUILD_SCRIPT = "firmware/build_firmware.sh"
CLI_GIVE = "pass --firmware FILE"  # how the command line hands over an image of its own


class ReleaseError(CliError):
    """No release could be found or fetched."""


class NoFirmwareError(ReleaseError):
    """Nothing to flash: no image given, none reachable, none cached."""


@dataclass(frozen=True)
class Release:
    version: str
    image: Path
    downloaded: bool  # False: it came from the cache
    note: str = ""


@dataclass(frozen=True)
class Releases:
    """Where images can come from, found before any board is touched, so that a flash with nothing to
    write fails at once and a reachable index is read once for every board of a batch."""

    url: str | None  # the releases location; None: none is set
    index: dict | None  # its latest.json, when it answered with one
    unreachable: str = ""  # why the location gave no index ("" when it did, or none is set)
    give: str = CLI_GIVE  # how this caller passes an image of its own, for the messages

    def nothing_for(self, chip: str | None) -> str:
        """The one line for "nothing to flash": how to get an image, then why none was found."""
        if self.url is None:
            why = f"no release is cached and no releases location is set ({RELEASES_URL_ENV})"
        elif self.index is None:
            why = f"the releases at {self.url} cannot be reached ({self.unreachable}) and none is cached"
        else:
            why = f"the release index {self.url}/{MANIFEST_NAME} lists no image for {chip} and none is cached"
        return (
            f"no firmware image{f' for the {chip}' if chip else ''}: {self.give}, or build one first with "
            f"{BUILD_SCRIPT} {chip or 'esp32s3'} MICROPYTHON_DIR (see `openbricks docs firmware`); {why}"
        )


def releases_url() -> str | None:
    value = os.environ.get(RELEASES_URL_ENV, "").strip() or DEFAULT_RELEASES_URL
    return value.rstrip("/") if value else None


def find_releases(chip: str | None = None, give: str = CLI_GIVE) -> Releases:
    """The releases to take an image from, or NoFirmwareError when there is nothing for `chip` (None: for
    any chip). With no location set, the network is not touched: only the cache is looked at."""
    url = releases_url()
    index, unreachable = None, ""
    if url is not None:
        try:
            index = _read_index(url)
        except (urllib.error.URLError, OSError, ValueError) as exc:
            unreachable = _reason(exc)
    releases = Releases(url, index, unreachable, give)
    listed = index is not None and (chip is None or chip in index["images"])
    if not listed and _newest_cached(chip) is None:
        raise NoFirmwareError(releases.nothing_for(chip))
    return releases


def newest_release(
    chip: str, releases: Releases | None = None, log: Callable[[str], None] = lambda _line: None
) -> Release:
    """The newest release image for `chip`, fetched with its signature unless already cached; the newest
    cached one when the location is unset, unreachable or lists none for the chip."""
    releases = releases if releases is not None else find_releases(chip)
    name = releases.index["images"].get(chip) if releases.index is not None else None
    if name:
        return _fetch_release(releases, str(releases.index["version"]), str(name), log)
    cached = _newest_cached(chip)
    if cached is None:
        raise NoFirmwareError(releases.nothing_for(chip))
    if releases.url is None:
        note = "no releases location is set; using the newest cached image"
    elif releases.index is None:
        note = f"releases unreachable ({releases.unreachable}); using the cached one"
    else:
        note = f"the release index lists no image for {chip}; using the cached one"
    return Release(cached[0], cached[1], False, note)


def _fetch_release(releases: Releases, version: str, name: str, log: Callable[[str], None]) -> Release:
    base = releases.url
    folder = firmware_cache_dir() / version
    folder.mkdir(parents=True, exist_ok=True)
    image = folder / Path(name).name
    if image.is_file():
        return Release(version, image, False)
    log(f"download {base}/{name}")
    try:
        data = _fetch(f"{base}/{name}", IMAGE_TIMEOUT_S)
    except (urllib.error.URLError, OSError) as exc:
        raise ReleaseError(
            f"downloading {base}/{name} failed ({_reason(exc)}); try again or {releases.give}"
        ) from None
    try:
        signature = _fetch(f"{base}/{name}{SIGNATURE_SUFFIX}", IMAGE_TIMEOUT_S)
        _save(signature, image.with_name(image.name + SIGNATURE_SUFFIX))
    except (urllib.error.URLError, OSError):
        pass  # unsigned: it will flash as (customized)
    _save(data, image)
    return Release(version, image, True)


def _read_index(base: str) -> dict:
    index = json.loads(_fetch(f"{base}/{MANIFEST_NAME}", INDEX_TIMEOUT_S))
    if not (isinstance(index, dict) and "version" in index and isinstance(index.get("images"), dict)):
        raise ValueError(f"{MANIFEST_NAME} is not a release index (no version and images)")
    return index


def _fetch(url: str, timeout_s: float) -> bytes:
    with urllib.request.urlopen(url, timeout=timeout_s) as response:
        return response.read()


def _save(data: bytes, path: Path) -> None:
    part = path.with_name(path.name + ".part")
    part.write_bytes(data)
    os.replace(part, path)  # a half-downloaded image never looks cached


def _newest_cached(chip: str | None) -> tuple[str, Path] | None:
    """The newest cached release image for `chip` (None: for any chip), as (version, path)."""
    root = firmware_cache_dir()
    found = []
    for image in root.glob("*/*.bin"):
        named = release_chip(image.name)
        if named is not None and (chip is None or named == chip):
            found.append((parse_version(image.parent.name), image.parent.name, image))
    if not found:
        return None
    _, version, image = max(found)
    return version, image


def _reason(exc: BaseException) -> str:
    reason = getattr(exc, "reason", None)
    return str(reason if reason is not None else exc)
