"""Newest release: fetched from the configured location once, then served from the cache."""

import json

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
    with pytest.raises(releases.ReleaseError, match="none is cached.*--firmware"):
        releases.newest_release("esp32")


def test_a_release_without_the_chip_is_reported(release_dir):
    (release_dir / "latest.json").write_text(json.dumps({"version": "3.0.0", "images": {"esp32": "x.bin"}}))
    with pytest.raises(releases.ReleaseError, match="no image for esp32s3"):
        releases.newest_release("esp32s3")
