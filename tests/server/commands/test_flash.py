"""`openbricks flash` end to end: a fake esptool does the chip work, a virtual hub's pty stands in for
the board's USB port (so the name and provenance really go through the hub's raw REPL), and images
are built by the test for both chips and signed with a key pair of its own."""

import os
import subprocess
import sys
import time
from pathlib import Path

import pytest

from openbricks_server.flash import signing

from ..flash.images import build_image
from .conftest import cli, console_holding

pytestmark = pytest.mark.e2e


@pytest.fixture
def keys(tmp_path):
    private, public = tmp_path / "release.pem", tmp_path / "release.pub"
    signing.generate_key_pair(private, public)
    return private, public


def flash_env(board, fake_esptool, public_key, chip="ESP32-S3"):
    fake = {name: os.environ[name] for name in ("OPENBRICKS_ESPTOOL", "FAKE_ESPTOOL_LOG")}
    return dict(board.env, OPENBRICKS_FIRMWARE_PUBKEY=str(public_key), FAKE_ESPTOOL_CHIP=chip, **fake)


def image(tmp_path, chip, version, key=None, name="firmware.bin"):
    path = tmp_path / name
    path.write_bytes(build_image(chip, version=version))
    if key is not None:
        signing.sign_file(key, path)
    return path


def test_a_signed_image_is_written_at_its_offset_and_the_hub_is_named_official(
    tmp_path,
    board,
    keys,
    fake_esptool,
    monkeypatch,
):
    private, public = keys
    env = flash_env(board, fake_esptool, public)
    firmware = image(tmp_path, "esp32s3", "2.8.0", key=private)
    done = cli(
        env, "flash", "--name", "RobotA", "--port", board.pty, "--firmware", str(firmware), "--with-qtr-init"
    )
    assert done.returncode == 0, done.stderr
    assert fake_esptool.commands() == ["chip-id", "erase-flash", "write-flash"]
    write = fake_esptool.calls()[-1]
    assert write[write.index("write-flash") :] == ["write-flash", "-z", "0x0", str(firmware)]
    assert write[write.index("--baud") + 1] == "460800"
    err = done.stderr
    assert "firmware 2.7.1 (customized)" in err  # what was on the hub before
    assert "esp32s3, version 2.8.0, written at 0x0 (official: signature verified)" in err
    assert "writing 100 %" in err
    assert "hub name 'RobotA' written and read back" in err
    assert board.nvs_blob("openbricks", "hub_name") == b"RobotA"
    assert board.nvs_blob("ob_firmware", "provenance") == b"official 2.7.1"
    assert b'"format": "openbricks-qtr-1"' in board.flash_file("/qtr.cal")


def test_an_image_for_the_other_chip_is_refused_before_anything_is_written(
    tmp_path, board, keys, fake_esptool
):
    env = flash_env(board, fake_esptool, keys[1])
    classic = image(tmp_path, "esp32", "2.8.0")
    done = cli(env, "flash", "--name", "RobotA", "--port", board.pty, "--firmware", str(classic))
    assert done.returncode == 1
    assert "is built for esp32 but the board on" in done.stderr and "cannot boot" in done.stderr
    assert fake_esptool.commands() == ["chip-id"]


def test_a_classic_esp32_image_goes_to_0x1000_unsigned_means_customized(tmp_path, board, keys, fake_esptool):
    env = flash_env(board, fake_esptool, keys[1], chip="ESP32")
    classic = image(tmp_path, "esp32", "2.8.0")
    done = cli(
        env, "flash", "--name", "RobotB", "--port", board.pty, "--firmware", str(classic), "--skip-erase"
    )
    assert done.returncode == 0, done.stderr
    assert fake_esptool.commands() == ["chip-id", "write-flash"]
    assert fake_esptool.calls()[-1][-2:] == ["0x1000", str(classic)]
    assert "(customized: no signature file next to the image)" in done.stderr
    assert board.nvs_blob("ob_firmware", "provenance") == b"customized 2.7.1"


def test_the_same_or_an_older_version_needs_yes(tmp_path, board, keys, fake_esptool):
    env = flash_env(board, fake_esptool, keys[1])
    same = image(tmp_path, "esp32s3", "2.7.1", name="openbricks-esp32s3-firmware-2.7.1.bin")
    done = cli(env, "flash", "--name", "RobotA", "--port", board.pty, "--firmware", str(same))
    assert done.returncode == 1 and "is the same version as the firmware on the hub" in done.stderr
    assert "pass --yes" in done.stderr and "write-flash" not in fake_esptool.commands()
    done = cli(env, "flash", "--name", "RobotA", "--port", board.pty, "--firmware", str(same), "--yes")
    assert done.returncode == 0, done.stderr
    assert "write-flash" in fake_esptool.commands()


def test_names_that_cannot_be_advertised_are_refused(tmp_path, board, keys, fake_esptool):
    env = flash_env(board, fake_esptool, keys[1])
    done = cli(env, "flash", "--name", "x" * 30, "--port", board.pty)
    assert done.returncode == 2 and "a Bluetooth advertisement carries at most 26" in done.stderr
    assert fake_esptool.calls() == []


def test_with_no_image_anywhere_flash_stops_at_once_saying_how_to_build_one(tmp_path, fake_esptool):
    """No --firmware, no release cached, no releases location: the installed command ends before it
    looks for a port, in one line that says to build an image or pass one."""
    home = tmp_path / "home"
    home.mkdir()
    env = {
        "PATH": os.environ["PATH"],
        "HOME": str(home),
        "OPENBRICKS_CACHE_DIR": str(home / "cache"),
        "OPENBRICKS_DATA_DIR": str(home / "data"),
        "OPENBRICKS_RUNTIME_DIR": str(home / "run"),
        "OPENBRICKS_ESPTOOL": os.environ["OPENBRICKS_ESPTOOL"],  # records any chip work, should any start
        "FAKE_ESPTOOL_LOG": os.environ["FAKE_ESPTOOL_LOG"],
    }
    command = Path(sys.executable).with_name("openbricks")  # the console script, as a user runs it
    started = time.monotonic()
    done = subprocess.run(
        [str(command), "flash", "--name", "X"], capture_output=True, text=True, env=env, timeout=30
    )
    took_s = time.monotonic() - started
    assert done.returncode == 1, done.stderr
    lines = done.stderr.splitlines()
    assert len(lines) == 1 and done.stdout == "", done.stderr
    assert lines[0].startswith("openbricks flash: error: no firmware image: ")
    assert "firmware/build_firmware.sh" in lines[0] and "--firmware" in lines[0]
    assert "Traceback" not in done.stderr
    assert fake_esptool.calls() == []  # no board was probed for an image that cannot come
    assert not (home / "cache").exists()
    assert took_s < 1.0, f"openbricks flash took {took_s:.2f} s to say there is no image"


def test_without_firmware_the_newest_release_for_the_chip_is_downloaded_and_cached(
    tmp_path, board, keys, fake_esptool
):
    import json

    private, public = keys
    releases = tmp_path / "releases"
    releases.mkdir()
    names = {}
    for chip in ("esp32", "esp32s3"):
        names[chip] = f"openbricks-{chip}-firmware-2.9.0.bin"
        image(releases, chip, "2.9.0", key=private, name=names[chip])
    (releases / "latest.json").write_text(json.dumps({"version": "2.9.0", "images": names}))
    env = dict(
        flash_env(board, fake_esptool, public),
        OPENBRICKS_RELEASES_URL=releases.as_uri(),
        OPENBRICKS_CACHE_DIR=str(tmp_path / "cache"),
    )
    done = cli(env, "flash", "--name", "RobotA", "--port", board.pty, "--verbose")
    assert done.returncode == 0, done.stderr
    cached = tmp_path / "cache" / "firmware" / "2.9.0" / names["esp32s3"]
    assert cached.is_file() and fake_esptool.calls()[-1][-1] == str(cached)
    assert "version 2.9.0 (downloaded)" in done.stderr and "official: signature verified" in done.stderr
    assert f"cache {cached}" in done.stderr  # --verbose shows cache paths ...
    assert "$ " in done.stderr and "write-flash -z 0x0" in done.stderr  # ... and esptool command lines


def test_a_port_the_console_holds_is_refused_with_where_to_flash_it(tmp_path, board, keys, fake_esptool):
    env = flash_env(board, fake_esptool, keys[1])
    with console_holding(env, board.pty, tmp_path) as (url, env):
        firmware = image(tmp_path, "esp32s3", "2.8.0")
        done = cli(env, "flash", "--name", "RobotA", "--port", board.pty, "--firmware", str(firmware))
        assert done.returncode == 1
        assert (
            f"the console ({url}) holds hub pts-" in done.stderr
            and "flash it from the console" in done.stderr
        )
        assert fake_esptool.calls() == []
