"""Firmware images built byte by byte, laid out as ESP-IDF lays out a merged MicroPython firmware.bin."""

import struct

CHIP_IDS = {"esp32": 0x0000, "esp32s3": 0x0009, "esp32c3": 0x0005}
BOOT_OFFSETS = {"esp32": 0x1000, "esp32s3": 0x0, "esp32c3": 0x0}
APP_ADDRESS = 0x10000


def _image_header(chip_id: int) -> bytes:
    header = struct.pack("<BBBBI", 0xE9, 3, 2, 0x20, 0x40080400)  # magic, segments, mode, size/freq, entry
    # extended header: wp pin, drive settings, chip id, min rev, min/max rev full, reserved, hash appended
    extended = struct.pack("<B3sHBHH4sB", 0xEE, b"\0\0\0", chip_id, 0, 0, 0xFFFF, b"\0" * 4, 1)
    return header + extended


def _partition_entry(kind: int, subtype: int, offset: int, size: int, label: bytes) -> bytes:
    return struct.pack("<2sBBII16sI", b"\xaa\x50", kind, subtype, offset, size, label.ljust(16, b"\0"), 0)


def build_image(
    chip: str,
    partition_table_at: int = 0x8000,
    version: str = "2.7.1",
    base: int | None = None,
    app_bytes: int = 4096,
) -> bytes:
    """A merged image for `chip` meant for flash address `base` (the chip's bootloader address by default)."""
    base = BOOT_OFFSETS[chip] if base is None else base
    data = bytearray(b"\xff" * (APP_ADDRESS - base + app_bytes))
    data[0:24] = _image_header(CHIP_IDS[chip])
    table = partition_table_at - base
    entries = _partition_entry(1, 2, 0x9000, 0x6000, b"nvs") + _partition_entry(
        0, 0, APP_ADDRESS, 0x1F0000, b"factory"
    )
    data[table : table + len(entries)] = entries
    app = APP_ADDRESS - base
    data[app : app + 24] = _image_header(CHIP_IDS[chip])
    # esp_app_desc_t right after the first segment header: magic, secure version, reserved, version[32]
    desc = struct.pack("<II8s32s32s", 0xABCD5432, 0, b"\0" * 8, version.encode(), b"openbricks")
    data[app + 32 : app + 32 + len(desc)] = desc
    return bytes(data)
