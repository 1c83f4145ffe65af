"""What a firmware file is, read from its own bytes: which chip it was built for and where it goes.

A MicroPython ESP32 `firmware.bin` is a merged image that starts with the second-stage bootloader and
must be written at the bootloader's flash address: 0x1000 on the classic ESP32 (and S2), 0x0 on the
S3 and the RISC-V chips. Writing it at the wrong one leaves a chip that cannot boot, so the offset is
never taken from the user; it is derived from the image:

- the bootloader's image header (magic 0xE9) carries the target chip id in its extended header
  (bytes 12-13, little endian), which fixes the bootloader address;
- the partition table (entries start with 0xAA 0x50) must then sit at 0x8000 or 0x9000 of flash,
  i.e. at (table address - offset) in the file. Finding it there confirms the image is a complete,
  correctly based firmware and not an app-only binary or a dump taken at another base.
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from pathlib import Path

from openbricks_server.errors import CliError

ESP_IMAGE_MAGIC = 0xE9
PARTITION_MAGIC = b"\xaa\x50"
PARTITION_TABLE_ADDRESSES = (0x8000, 0x9000)  # default, and where a bigger bootloader pushes it
APP_DESC_MAGIC = b"\x32\x54\xcd\xab"  # esp_app_desc_t.magic_word 0xABCD5432, little endian
_HEADER_BYTES = 24  # image header (8) + extended header (16)

# esp_chip_id_t values from the extended header -> (esptool chip name, bootloader flash address)
CHIPS = {
    0x0000: ("esp32", 0x1000),
    0x0002: ("esp32s2", 0x1000),
    0x0005: ("esp32c3", 0x0),
    0x0009: ("esp32s3", 0x0),
    0x000C: ("esp32c2", 0x0),
    0x000D: ("esp32c6", 0x0),
    0x0010: ("esp32h2", 0x0),
    0x0012: ("esp32p4", 0x2000),
}
SUPPORTED_CHIPS = ("esp32", "esp32s3")
_RELEASE_NAME = re.compile(r"openbricks-(?P<chip>esp32\w*)-firmware-v?(?P<version>\d+\.\d+\.\d+)\.bin$")


class ImageError(CliError):
    """The file is not a firmware image this hub can take."""


@dataclass(frozen=True)
class FirmwareImage:
    path: Path
    chip: str  # esptool's name: "esp32", "esp32s3"
    offset: int  # flash address of the first byte
    partition_table: int  # flash address of the partition table
    size: int
    version: str | None  # from the release file name, or the app descriptor; None if neither says

    @property
    def offset_hex(self) -> str:
        return f"0x{self.offset:x}"


def inspect_image(path: str | Path) -> FirmwareImage:
    """Chip, offset and version of the firmware file at `path`; ImageError if it is not a full image."""
    path = Path(path)
    try:
        data = path.read_bytes()
    except FileNotFoundError:
        raise ImageError(f"{path}: no such firmware file; check the path given to --firmware") from None
    except IsADirectoryError:
        raise ImageError(f"{path} is a folder: give the firmware .bin file itself") from None
    except OSError as exc:
        raise ImageError(f"{path}: cannot read it ({exc.strerror})") from None
    return inspect_bytes(data, path)


def inspect_bytes(data: bytes, path: Path) -> FirmwareImage:
    if len(data) < _HEADER_BYTES or data[0] != ESP_IMAGE_MAGIC:
        raise ImageError(
            f"{path.name} is not an ESP32 firmware image (it does not start with the 0xE9 image header): "
            "use the firmware.bin of the build or a release's openbricks-<chip>-firmware-<version>.bin"
        )
    chip_id = int.from_bytes(data[12:14], "little")
    if chip_id not in CHIPS:
        raise ImageError(
            f"{path.name} is built for an unknown chip (id {chip_id}); openbricks runs on ESP32 and ESP32-S3"
        )
    chip, offset = CHIPS[chip_id]
    if chip not in SUPPORTED_CHIPS:
        raise ImageError(f"{path.name} is built for {chip}; openbricks hubs are ESP32 or ESP32-S3")
    table = _find_partition_table(data, offset)
    if table is None:
        other = [o for o in {0x0, 0x1000} if o != offset and _find_partition_table(data, o) is not None]
        if other:
            raise ImageError(
                f"{path.name} says it is for {chip} (written at 0x{offset:x}) but its partition table "
                f"sits where an image for 0x{other[0]:x} has it: the file is inconsistent; rebuild it "
                "with firmware/build_firmware.sh"
            )
        raise ImageError(
            f"{path.name} has no partition table at 0x8000 or 0x9000 of flash: it is not a complete firmware "
            "(an app-only micropython.bin?); use the build's firmware.bin"
        )
    return FirmwareImage(path, chip, offset, table, len(data), _version(path.name, data))


def _find_partition_table(data: bytes, offset: int) -> int | None:
    for address in PARTITION_TABLE_ADDRESSES:
        at = address - offset
        if 0 <= at and data[at : at + 2] == PARTITION_MAGIC:
            return address
    return None


def _version(filename: str, data: bytes) -> str | None:
    """The release name's version, else the app descriptor's version string if it looks like one."""
    named = _RELEASE_NAME.search(filename)
    if named:
        return named.group("version")
    at = data.find(APP_DESC_MAGIC)
    if at < 0:
        return None
    # esp_app_desc_t: magic(4) secure_version(4) reserved(8) version[32] ...
    raw = data[at + 16 : at + 48].split(b"\0", 1)[0].decode("ascii", "replace")
    match = re.match(r"v?(\d+\.\d+\.\d+)", raw)
    return match.group(1) if match else None


def release_chip(filename: str) -> str | None:
    named = _RELEASE_NAME.search(filename)
    return named.group("chip") if named else None


def parse_version(text: str) -> tuple[int, ...]:
    return tuple(int(part) for part in re.findall(r"\d+", text)[:3])
