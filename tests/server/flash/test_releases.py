"""Releases: fetched from the configured location once, then served from the cache; with no location set
the network is never touched, and a location that does not answer costs its short timeout, no more."""

import json
import socket
import threading
import time
import urllib.request

import pytest

from openbricks_server.flash import releases
from openbricks_server.flash.image import inspect_image

from .images import build_image


@pytest.fixture
def release_dir(tmp_path, monkeypatch):
    folder = tmp_path / "releases"
    folder.mkdir()
    monkeypatch.setenv("OPENBRICKS_CACHE_DIR", str(tmp_path / "cache"))
    monkeypatch.setenv(releases.RELEASES_URL_ENV, folder.as_uri())
    return folder


def publish(folder, version):
    names = {}
    for chip in ("esp32", "esp32s3"):
        name = f"openbricks-{chip}-firmware-{version}.bin"
        (folder / name).write_bytes(build_image(chip, version=version))
        (folder / f"{name}.sig").write_bytes(b"\x01" * 64)
        names[chip] = name
    (folder / "latest.json").write_text(json.dumps({"version": version, "images": names}))


def test_download_then_cache_then_offline_fallback(release_dir, tmp_path, monkeypatch):
    publish(release_dir, "2.7.1")
    first = releases.newest_release("esp32s3")
    assert first.downloaded and first.version == "2.7.1"
    assert first.image.parent == tmp_path / "cache" / "firmware" / "2.7.1"
    assert first.image.with_name(first.image.name + ".sig").is_file()
    assert inspect_image(first.image).chip == "esp32s3"
    again = releases.newest_release("esp32s3")
    assert not again.downloaded and again.image == first.image
    monkeypatch.setenv(releases.RELEASES_URL_ENV, (tmp_path / "gone").as_uri())
    offline = releases.newest_release("esp32s3")
    assert offline.image == first.image and "unreachable" in offline.note


def test_unreachable_with_an_empty_cache_says_what_to_do(release_dir):
    with pytest.raises(releases.NoFirmwareError) as refused:
        releases.newest_release("esp32")
    message = str(refused.value)
    assert "pass --firmware FILE" in message and "firmware/build_firmware.sh esp32 " in message
    assert "cannot be reached" in message and "none is cached" in message and "\n" not in message


def test_a_release_without_the_chip_is_reported(release_dir):
    (release_dir / "latest.json").write_text(json.dumps({"version": "3.0.0", "images": {"esp32": "x.bin"}}))
    with pytest.raises(releases.ReleaseError, match="no image for esp32s3"):
        releases.newest_release("esp32s3")


@pytest.fixture
def no_network(monkeypatch):
    def refuse(*_args, **_kwargs):
        raise AssertionError("the network was asked")

    monkeypatch.setattr(urllib.request, "urlopen", refuse)


def test_no_location_is_set_by_default_so_nothing_is_fetched_and_the_refusal_says_how_to_build(
    tmp_path, monkeypatch, no_network
):
    monkeypatch.delenv(releases.RELEASES_URL_ENV, raising=False)
    monkeypatch.setenv("OPENBRICKS_CACHE_DIR", str(tmp_path / "cache"))
    assert releases.releases_url() is None
    with pytest.raises(releases.NoFirmwareError) as refused:
        releases.find_releases()
    assert str(refused.value) == (
        "no firmware image: pass --firmware FILE, or build one first with firmware/build_firmware.sh esp32s3 "
        "MICROPYTHON_DIR (see `openbricks docs firmware`); no release is cached and no releases location "
        "is set (OPENBRICKS_RELEASES_URL)"
    )
    assert not (tmp_path / "cache").exists()  # looking left nothing behind


def test_with_no_location_set_a_cached_release_is_used_and_says_so(tmp_path, monkeypatch, no_network):
    monkeypatch.delenv(releases.RELEASES_URL_ENV, raising=False)
    monkeypatch.setenv("OPENBRICKS_CACHE_DIR", str(tmp_path / "cache"))
    for version in ("2.7.1", "2.10.0"):
        folder = tmp_path / "cache" / "firmware" / version
        folder.mkdir(parents=True)
        image = folder / f"openbricks-esp32-firmware-{version}.bin"
        image.write_bytes(build_image("esp32", version=version))
    found = releases.find_releases("esp32")
    with pytest.raises(releases.NoFirmwareError, match="no firmware image for the esp32s3"):
        releases.find_releases("esp32s3")
    release = releases.newest_release("esp32", found)
    assert release.version == "2.10.0" and not release.downloaded
    assert "no releases location is set" in release.note


def test_a_location_that_never_answers_costs_the_index_timeout_only(tmp_path, monkeypatch):
    silent = socket.create_server(("127.0.0.1", 0))  # accepts, never answers
    accepted = []
    threading.Thread(target=lambda: accepted.append(silent.accept()), daemon=True).start()
    monkeypatch.setenv(releases.RELEASES_URL_ENV, f"http://127.0.0.1:{silent.getsockname()[1]}/")
    monkeypatch.setenv("OPENBRICKS_CACHE_DIR", str(tmp_path / "cache"))
    monkeypatch.setattr(releases, "INDEX_TIMEOUT_S", 0.3)
    started = time.monotonic()
    try:
        with pytest.raises(releases.NoFirmwareError, match="cannot be reached .*timed out"):
            releases.find_releases()
    finally:
        silent.close()
    assert time.monotonic() - started < 2
