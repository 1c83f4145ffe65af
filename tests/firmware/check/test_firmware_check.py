"""make firmware-check, run as CI runs it: the hub image's C compiled for Xtensa against ESP-IDF 5.5.4
and MicroPython 1.28's esp32 port, and the mistakes it exists to catch, caught with file and line."""

import shutil
import subprocess
import sys
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[3]
CHECK = REPO / "firmware" / "check"
NATIVE = REPO / "firmware" / "native"
MODULE = NATIVE / "user_c_modules" / "openbricks"
GLUE = ("mp_pcnt_esp32.c", "mp_spi_esp32.c", "mp_hard_timer_esp32.c", "mp_uart_esp32.c")
LIMIT_S = 600

pytestmark = pytest.mark.skipif(
    shutil.which("xtensa-lx106-elf-gcc") is None,
    reason="needs Debian's gcc-xtensa-lx106 (make setup installs it)",
)


def run_check(*args):
    return subprocess.run(
        [sys.executable, str(CHECK), *args], capture_output=True, text=True, timeout=LIMIT_S, cwd=REPO
    )


def broken_copy(tmp_path, name, old, new):
    """A copy of a glue file with one line changed; returns (path, the changed line's number)."""
    text = (MODULE / name).read_text()
    assert text.count(old) == 1, f"{old!r} is not in {name} exactly once"
    copy = tmp_path / name
    copy.write_text(text.replace(old, new))
    line = text[: text.index(old)].count("\n") + 1
    return copy, line


def test_a_wrong_argument_type_to_an_esp_idf_function_fails_with_file_and_line(tmp_path):
    # pcnt_unit_get_count() stores an int; a 16-bit variable is the classic mistake.
    copy, line = broken_copy(tmp_path, "mp_pcnt_esp32.c", "    int value;\n", "    int16_t value;\n")
    result = run_check("--target", "esp32s3", "--only", str(copy))
    assert result.returncode == 1
    assert f"{copy}:" in result.stderr
    assert "pcnt_unit_get_count" in result.stderr
    assert "incompatible-pointer-types" in result.stderr
    assert f"{copy}:{line + 1}:" in result.stderr  # the call, on the line after the declaration
    assert "0 of 1 C files compiled" in result.stdout


def test_a_misspelt_config_macro_fails_with_file_and_line(tmp_path):
    copy, line = broken_copy(
        tmp_path,
        "mp_uart_esp32.c",
        "    TickType_t ticks = pdMS_TO_TICKS((timeout_us + 999u) / 1000u);\n",
        "    TickType_t ticks = (timeout_us + 999u) / 1000u * CONFIG_FREERTOS_HZ_ / 1000u;\n",
    )
    result = run_check("--target", "esp32", "--only", str(copy))
    assert result.returncode == 1
    assert f"{copy}:{line}:" in result.stderr
    assert "CONFIG_FREERTOS_HZ_" in result.stderr


def test_an_sdkconfig_key_esp_idf_does_not_know_fails_with_file_and_line(tmp_path):
    boards = tmp_path / "boards"
    shutil.copytree(REPO / "firmware" / "boards", boards)
    fragment = boards / "sdkconfig.ble"
    lines = fragment.read_text().splitlines()
    fragment.write_text("\n".join([*lines, "CONFIG_BT_NIMBLE_MAX_CONECTIONS=1"]) + "\n")
    result = run_check("--target", "esp32s3", "--boards", str(boards), "--only", str(MODULE / "mp_args.c"))
    assert result.returncode == 1
    assert f"{fragment}:{len(lines) + 1}: CONFIG_BT_NIMBLE_MAX_CONECTIONS is not an ESP-IDF 5.5.4 option" in (
        result.stderr
    )


def test_a_fragment_the_board_names_but_micropython_lacks_fails(tmp_path):
    boards = tmp_path / "boards"
    shutil.copytree(REPO / "firmware" / "boards", boards)
    cmake = boards / "openbricks_esp32" / "mpconfigboard.cmake"
    cmake.write_text(
        cmake.read_text().replace(
            "    boards/sdkconfig.base\n", "    boards/sdkconfig.base\n    boards/sdkconfig.usb\n"
        )
    )
    result = run_check("--target", "esp32", "--boards", str(boards), "--only", str(MODULE / "mp_args.c"))
    assert result.returncode == 1
    assert "sdkconfig fragment boards/sdkconfig.usb does not exist" in result.stderr
    assert f"{cmake}:" in result.stderr


@pytest.mark.e2e
def test_every_c_file_of_the_image_compiles_for_xtensa_on_both_boards():
    result = run_check()
    assert result.returncode == 0, result.stderr[-4000:]
    ours = sorted(NATIVE.glob("*.c")) + sorted(MODULE.glob("*.c"))
    for target in ("esp32", "esp32s3"):
        assert (
            f"firmware-check {target}: {len(ours)} of {len(ours)} C files compiled for Xtensa, 0 warnings"
            in (result.stdout)
        )
        objects = REPO / "build" / "firmware-check" / target / "obj"
        built = sorted(objects.rglob("*.o"))
        assert len(built) == len(ours)
        names = {o.stem for o in built}
        assert {Path(g).stem for g in GLUE} <= names
        for obj in built:
            header = subprocess.run(
                ["readelf", "-h", str(obj)], capture_output=True, text=True, check=True
            ).stdout
            assert "Tensilica Xtensa" in header, obj
        frozen = REPO / "build" / "firmware-check" / target / "frozen"
        assert (frozen / "openbricks" / "hub.mpy").is_file()
