"""The newest released firmware for a chip, downloaded once and kept under the cache dir.

A release location (OPENBRICKS_RELEASES_URL; http(s) or file URL) serves `latest.json`:

    {"version": "2.7.1",
     "images": {"esp32s3": "openbricks-esp32s3-firmware-2.7.1.bin",
                "esp32": "openbricks-esp32-firmware-2.7.1.bin"}}

and, beside it, each image and its `.sig`. Files land in `<cache>/firmware/<version>/`; an image already
there is not fetched again. Offline, the newest cached image for the chip is used, and the output says so.
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
DEFAULT_RELEASES_URL = "https://github.com/1e0ng/openbricks/releases/latest/download"
MANIFEST_NAME = "latest.json"
_TIMEOUT_S = 30


class ReleaseError(CliError):
    """No release could be found or fetched."""


@dataclass(frozen=True)
class Release:
    version: str
    image: Path
    downloaded: bool  # False: it came from the cache
    note: str = ""


def releases_url() -> str:
    return os.environ.get(RELEASES_URL_ENV, DEFAULT_RELEASES_URL).rstrip("/")


def _fetch(url: str) -> bytes:
    with urllib.request.urlopen(url, timeout=_TIMEOUT_S) as response:
        return response.read()


def _save(data: bytes, path: Path) -> None:
    part = path.with_name(path.name + ".part")
    part.write_bytes(data)
    os.replace(part, path)  # a half-downloaded image never looks cached


def newest_release(chip: str, log: Callable[[str], None] = lambda _line: None) -> Release:
    """Download (or reuse) the newest release image for `chip` and its signature."""
    base = releases_url()
    try:
        manifest = json.loads(_fetch(f"{base}/{MANIFEST_NAME}"))
        version = str(manifest["version"])
        name = manifest["images"][chip]
    except (urllib.error.URLError, OSError, ValueError) as exc:
        cached = _newest_cached(chip)
        if cached is None:
            raise ReleaseError(
                f"cannot reach the firmware releases at {base} ({_reason(exc)}) and none is cached: connect "
                "to the internet, set OPENBRICKS_RELEASES_URL, or pass --firmware FILE"
            ) from None
        return Release(
            cached[0], cached[1], False, f"releases unreachable ({_reason(exc)}); using the cached one"
        )
    except (KeyError, TypeError):
        raise ReleaseError(f"the release index {base}/{MANIFEST_NAME} lists no image for {chip}") from None
    folder = firmware_cache_dir() / version
    folder.mkdir(parents=True, exist_ok=True)
    image = folder / Path(name).name
    if image.is_file():
        return Release(version, image, False)
    log(f"download {base}/{name}")
    try:
        data = _fetch(f"{base}/{name}")
    except (urllib.error.URLError, OSError) as exc:
        raise ReleaseError(
            f"downloading {base}/{name} failed ({_reason(exc)}); try again or pass --firmware"
        ) from None
    try:
        _save(_fetch(f"{base}/{name}{SIGNATURE_SUFFIX}"), image.with_name(image.name + SIGNATURE_SUFFIX))
    except (urllib.error.URLError, OSError):
        pass  # unsigned: it will flash as (customized)
    _save(data, image)
    return Release(version, image, True)


def _newest_cached(chip: str) -> tuple[str, Path] | None:
    root = firmware_cache_dir()
    found = []
    for image in root.glob("*/*.bin"):
        if release_chip(image.name) == chip:
            found.append((parse_version(image.parent.name), image.parent.name, image))
    if not found:
        return None
    _, version, image = max(found)
    return version, image


def _reason(exc: BaseException) -> str:
    reason = getattr(exc, "reason", None)
    return str(reason if reason is not None else exc)
