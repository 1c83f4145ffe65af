"""esptool runs as a separate process; the chip and the write progress are read from its output."""

import asyncio
import os

import pytest

from openbricks_server.flash.esptool_runner import Esptool, EsptoolError, parse_chip, parse_progress


@pytest.mark.parametrize("style", ["v5", "v4"])
def test_chip_probe_and_write_progress_in_both_output_styles(tmp_path, fake_esptool, monkeypatch, style):
    monkeypatch.setenv("FAKE_ESPTOOL_STYLE", style)
    monkeypatch.setenv("FAKE_ESPTOOL_CHIP", "ESP32")
    tool = Esptool("/dev/ttyUSB7")
    assert asyncio.run(tool.probe_chip()) == "esp32"
    image = tmp_path / "fw.bin"
    image.write_bytes(b"\xe9" * 50_000)
    seen = []
    asyncio.run(tool.write("esp32", 921600, 0x1000, str(image), seen.append))
    assert seen[0] == 0.0 and seen[-1] == 100.0
    assert seen == sorted(seen) and len(seen) >= 10
    write = fake_esptool.calls()[-1]
    assert write[:6] == ["--chip", "esp32", "--port", "/dev/ttyUSB7", "--baud", "921600"]
    assert write[6:] == ["write-flash", "-z", "0x1000", str(image)]


def test_a_failing_esptool_reports_its_own_reason_and_a_hint(fake_esptool, monkeypatch):
    monkeypatch.setenv("FAKE_ESPTOOL_FAIL", "chip-id")
    with pytest.raises(EsptoolError, match="Failed to connect to ESP32-S3.*hold BOOT while pressing RESET"):
        asyncio.run(Esptool("/dev/ttyACM0").probe_chip())


def test_verbose_echoes_the_command_line(fake_esptool):
    echoed = []
    asyncio.run(Esptool("/dev/ttyACM0", echo=echoed.append).erase("esp32s3"))
    assert echoed[0].startswith("$ ") and echoed[0].endswith("--chip esp32s3 --port /dev/ttyACM0 erase-flash")


def test_parsers_ignore_other_lines():
    assert parse_chip(["Connecting....", "Chip is ESP32-S3 (QFN56) (revision v0.2)"]) == "esp32s3"
    assert parse_progress("Writing at 0x00010000 [====      ]  42.5% 1/2 bytes [00:01]") == 42.5
    assert parse_progress("Writing at 0x00010000... (7 %)") == 7.0
    assert parse_progress("Wrote 1000 bytes at 0x00010000 in 0.1 seconds (100 % done)") is None


def _running_with(argument: str) -> list[int]:
    """Processes whose command line contains `argument`."""
    found = []
    for entry in os.listdir("/proc"):
        if entry.isdigit():
            try:
                with open(f"/proc/{entry}/cmdline", "rb") as f:
                    if argument.encode() in f.read():
                        found.append(int(entry))
            except OSError:
                pass
    return found


def test_a_cancelled_write_kills_its_esptool(tmp_path, fake_esptool, monkeypatch):
    monkeypatch.setenv("FAKE_ESPTOOL_WRITE_S", "60")
    image = tmp_path / "cancelled-firmware.bin"
    image.write_bytes(b"\xe9" * 1000)

    async def main():
        started = asyncio.Event()
        write = asyncio.create_task(
            Esptool("/dev/ttyUSB7").write("esp32s3", 460800, 0, str(image), lambda _p: started.set())
        )
        await asyncio.wait_for(started.wait(), 30)
        assert _running_with(str(image))
        write.cancel()
        with pytest.raises(asyncio.CancelledError):
            await write

    asyncio.run(main())
    assert _running_with(str(image)) == []
