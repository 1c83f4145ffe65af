"""Firmware provenance: an image is "official" when its `.bin.sig` verifies against the shipped key.

Release images are signed with Ed25519 by the release pipeline, which holds the private key; the CLI
ships only the public half (`openbricks_server/keys/firmware_signing.pub`, PEM). A missing, malformed
or wrong signature makes the image "customized": provenance is a label, not a gate, so customized
images flash normally. The key can be pointed elsewhere with OPENBRICKS_FIRMWARE_PUBKEY (a PEM file),
which is how a fork ships its own releases and how the tests use a key pair of their own.

The signature file holds the 64 signature bytes, raw or base64-encoded.

    python -m openbricks_server.flash.signing keygen KEY.pem PUB.pem   # once, for a release pipeline
    python -m openbricks_server.flash.signing sign KEY.pem IMAGE.bin   # writes IMAGE.bin.sig
"""

from __future__ import annotations

import argparse
import base64
import binascii
import os
import sys
from dataclasses import dataclass
from pathlib import Path

OFFICIAL = "official"
CUSTOMIZED = "customized"
PUBLIC_KEY_ENV = "OPENBRICKS_FIRMWARE_PUBKEY"
SIGNATURE_SUFFIX = ".sig"
_SIGNATURE_BYTES = 64


@dataclass(frozen=True)
class Verdict:
    provenance: str  # OFFICIAL or CUSTOMIZED
    reason: str  # why, for the step output

    @property
    def official(self) -> bool:
        return self.provenance == OFFICIAL


def public_key_path() -> Path:
    override = os.environ.get(PUBLIC_KEY_ENV)
    if override:
        return Path(override).expanduser()
    return Path(__file__).resolve().parent.parent / "keys" / "firmware_signing.pub"


def signature_path(image: Path) -> Path:
    return image.with_name(image.name + SIGNATURE_SUFFIX)


def _load_public_key(path: Path):
    from cryptography.hazmat.primitives.asymmetric.ed25519 import Ed25519PublicKey
    from cryptography.hazmat.primitives.serialization import load_pem_public_key

    key = load_pem_public_key(path.read_bytes())
    if not isinstance(key, Ed25519PublicKey):
        raise ValueError(f"{path} is not an Ed25519 public key")
    return key


def _signature_bytes(raw: bytes) -> bytes | None:
    if len(raw) == _SIGNATURE_BYTES:
        return raw
    try:
        decoded = base64.b64decode(raw.strip(), validate=True)
    except (binascii.Error, ValueError):
        return None
    return decoded if len(decoded) == _SIGNATURE_BYTES else None


def verify(image: bytes, signature: bytes | None, key_path: Path | None = None) -> Verdict:
    """The provenance of `image` given its signature file's contents (None when there is none)."""
    from cryptography.exceptions import InvalidSignature

    if signature is None:
        return Verdict(CUSTOMIZED, "no signature file next to the image")
    sig = _signature_bytes(signature)
    if sig is None:
        return Verdict(CUSTOMIZED, "the signature file is not a 64-byte Ed25519 signature")
    key_path = key_path or public_key_path()
    try:
        key = _load_public_key(key_path)
    except (OSError, ValueError) as exc:
        return Verdict(CUSTOMIZED, f"the public key {key_path} is unusable ({exc})")
    try:
        key.verify(sig, image)
    except InvalidSignature:
        return Verdict(CUSTOMIZED, "the signature does not match this image and the shipped key")
    return Verdict(OFFICIAL, "signature verified")


def verify_file(image_path: Path) -> Verdict:
    sig_path = signature_path(image_path)
    signature = sig_path.read_bytes() if sig_path.is_file() else None
    return verify(image_path.read_bytes(), signature)


def generate_key_pair(private_path: Path, public_path: Path) -> None:
    from cryptography.hazmat.primitives import serialization
    from cryptography.hazmat.primitives.asymmetric.ed25519 import Ed25519PrivateKey

    key = Ed25519PrivateKey.generate()
    private_path.write_bytes(
        key.private_bytes(
            serialization.Encoding.PEM, serialization.PrivateFormat.PKCS8, serialization.NoEncryption()
        )
    )
    os.chmod(private_path, 0o600)
    public_path.write_bytes(
        key.public_key().public_bytes(
            serialization.Encoding.PEM, serialization.PublicFormat.SubjectPublicKeyInfo
        )
    )


def sign_file(private_path: Path, image_path: Path) -> Path:
    """Write `image_path`.sig (raw signature bytes) with the PEM private key at `private_path`."""
    from cryptography.hazmat.primitives.serialization import load_pem_private_key

    key = load_pem_private_key(private_path.read_bytes(), password=None)
    out = signature_path(image_path)
    out.write_bytes(key.sign(image_path.read_bytes()))
    return out


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(
        prog="python -m openbricks_server.flash.signing", description=__doc__.split("\n")[0]
    )
    sub = parser.add_subparsers(dest="action", required=True)
    keygen = sub.add_parser("keygen", help="create an Ed25519 key pair (PEM)")
    keygen.add_argument("private_key", type=Path)
    keygen.add_argument("public_key", type=Path)
    sign = sub.add_parser("sign", help="sign a firmware image, writing IMAGE.sig")
    sign.add_argument("private_key", type=Path)
    sign.add_argument("image", type=Path)
    check = sub.add_parser("verify", help="say whether an image is official")
    check.add_argument("image", type=Path)
    args = parser.parse_args(argv)
    if args.action == "keygen":
        generate_key_pair(args.private_key, args.public_key)
        print(f"wrote {args.private_key} (keep it secret) and {args.public_key}")
    elif args.action == "sign":
        print(f"wrote {sign_file(args.private_key, args.image)}")
    else:
        verdict = verify_file(args.image)
        print(f"{verdict.provenance}: {verdict.reason}")
        return 0 if verdict.official else 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
