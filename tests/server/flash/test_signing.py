"""Provenance with a real Ed25519 key pair: official only when the signature verifies."""

import base64

import pytest

from openbricks_server.flash import signing


@pytest.fixture
def keys(tmp_path, monkeypatch):
    private, public = tmp_path / "release.pem", tmp_path / "release.pub"
    signing.generate_key_pair(private, public)
    monkeypatch.setenv(signing.PUBLIC_KEY_ENV, str(public))
    return private


def test_a_signed_image_is_official_and_any_change_makes_it_customized(tmp_path, keys):
    image = tmp_path / "fw.bin"
    image.write_bytes(b"\xe9" + bytes(range(256)) * 10)
    signing.sign_file(keys, image)
    assert signing.verify_file(image).provenance == "official"
    image.write_bytes(image.read_bytes()[:-1] + b"\x00")
    verdict = signing.verify_file(image)
    assert verdict.provenance == "customized" and "does not match" in verdict.reason


def test_base64_signatures_verify_too(tmp_path, keys):
    image = tmp_path / "fw.bin"
    image.write_bytes(b"\xe9firmware")
    raw = signing.sign_file(keys, image).read_bytes()
    signing.signature_path(image).write_bytes(base64.b64encode(raw) + b"\n")
    assert signing.verify_file(image).official


def test_missing_or_garbage_signatures_and_other_keys_mean_customized(tmp_path, keys, monkeypatch):
    image = tmp_path / "fw.bin"
    image.write_bytes(b"\xe9firmware")
    assert "no signature file" in signing.verify_file(image).reason
    signing.signature_path(image).write_bytes(b"not a signature")
    assert "not a 64-byte" in signing.verify_file(image).reason
    signing.sign_file(keys, image)
    other_private, other_public = tmp_path / "other.pem", tmp_path / "other.pub"
    signing.generate_key_pair(other_private, other_public)
    monkeypatch.setenv(signing.PUBLIC_KEY_ENV, str(other_public))
    assert signing.verify_file(image).provenance == "customized"


def test_the_shipped_public_key_is_an_ed25519_key(monkeypatch):
    monkeypatch.delenv(signing.PUBLIC_KEY_ENV, raising=False)
    assert signing.public_key_path().name == "firmware_signing.pub"
    assert signing._load_public_key(signing.public_key_path()) is not None
