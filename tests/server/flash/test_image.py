"""The write offset and the chip come from the image itself; inconsistent files are refused."""

import pytest

from openbricks_server.flash.image import ImageError, inspect_image

from .images import build_image


@pytest.mark.parametrize(
    ("chip", "table_at", "offset"),
    [
        ("esp32s3", 0x8000, 0x0),
        ("esp32s3", 0x9000, 0x0),
        ("esp32", 0x8000, 0x1000),
        ("esp32", 0x9000, 0x1000),
    ],
)
def test_chip_and_offset_are_read_from_the_image(tmp_path, chip, table_at, offset):
    path = tmp_path / "firmware.bin"
    path.write_bytes(build_image(chip, partition_table_at=table_at, version="2.6.0"))
    image = inspect_image(path)
    assert (image.chip, image.offset, image.partition_table) == (chip, offset, table_at)
    assert image.version == "2.6.0"  # from the app descriptor when the file name says nothing


def test_a_release_file_name_gives_the_version(tmp_path):
    path = tmp_path / "openbricks-esp32s3-firmware-2.7.1.bin"
    path.write_bytes(build_image("esp32s3", version="custom-build"))
    assert inspect_image(path).version == "2.7.1"


def test_an_s3_header_on_an_image_laid_out_for_0x1000_is_refused(tmp_path):
    path = tmp_path / "odd.bin"
    path.write_bytes(build_image("esp32s3", base=0x1000))
    with pytest.raises(ImageError, match="says it is for esp32s3 .*inconsistent"):
        inspect_image(path)


def test_app_only_images_and_other_files_are_refused(tmp_path):
    app_only = tmp_path / "micropython.bin"
    app_only.write_bytes(build_image("esp32s3")[0x10000:])
    with pytest.raises(ImageError, match="no partition table"):
        inspect_image(app_only)
    text = tmp_path / "notes.bin"
    text.write_bytes(b"hello world, not firmware at all")
    with pytest.raises(ImageError, match="not an ESP32 firmware image"):
        inspect_image(text)
    with pytest.raises(ImageError, match="no such firmware file"):
        inspect_image(tmp_path / "missing.bin")


def test_images_for_chips_openbricks_does_not_run_on_are_refused(tmp_path):
    path = tmp_path / "c3.bin"
    path.write_bytes(build_image("esp32c3"))
    with pytest.raises(ImageError, match="built for esp32c3"):
        inspect_image(path)
