"""The firmware tree, checked as far as it can be without ESP-IDF.

- firmware/manifest.py runs against a stand-in of MicroPython's manifest API that records what would
  be frozen, so a runtime module left out of the image fails here, not on a hub.
- The board definitions carry the facts the runtime relies on: BLE on, WiFi off, a machine string
  the runtime reads the chip from, the GPIO map's I2C pins.
- build_firmware.sh refuses clearly without MicroPython or ESP-IDF, and with stand-in `make` and
  `idf.py` on PATH it is seen building mpy-cross, then the board with our user C module.
- Everything frozen compiles with the real mpy-cross, as the image build does.
- The frozen main.py, run with the hardware fakes, wires the hub and hands over to the launcher.
"""

import os
import re
import subprocess
import sys
import textwrap
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
FIRMWARE = ROOT / "firmware"
BOARDS = FIRMWARE / "boards"
BUILD_SCRIPT = FIRMWARE / "build_firmware.sh"
BOARD_CHIPS = {"openbricks_esp32": "esp32", "openbricks_esp32s3": "esp32s3"}


# --- the manifest -------------------------------------------------------------------------------


class ManifestRecorder:
    """Just enough of MicroPython's manifestfile semantics: paths relative to the manifest file,
    $(VAR) substitution, package() freezing every .py below the package, names relative to base."""

    def __init__(self, variables):
        self.variables = variables
        self.frozen = {}  # frozen name -> source file
        self.port_freezes = []
        self.includes = []
        self.requires = []
        self._dirs = []

    def run(self, manifest):
        manifest = Path(manifest)
        self._dirs.append(manifest.parent)
        api = {
            name: getattr(self, name)
            for name in ("freeze", "include", "require", "package", "module", "metadata")
        }
        exec(compile(manifest.read_text(), str(manifest), "exec"), api)
        self._dirs.pop()

    def _path(self, path):
        for name, value in self.variables.items():
            path = path.replace(f"$({name})", str(value))
        return (self._dirs[-1] / path).resolve()

    def metadata(self, **kwargs):
        pass

    def freeze(self, path, script=None, opt=None):
        self.port_freezes.append((path, script))

    def include(self, path, **kwargs):
        self.includes.append(path)

    def require(self, name, **kwargs):
        self.requires.append(name)

    def package(self, package_path, files=None, base_path=".", opt=None):
        base = self._path(base_path)
        root = base / package_path
        assert root.is_dir(), f"package() names {root}, which does not exist"
        sources = sorted(root.rglob("*.py")) if files is None else [root / f for f in files]
        for source in sources:
            if "__pycache__" not in source.parts:
                self.frozen[source.relative_to(base).as_posix()] = source

    def module(self, module_path, base_path=".", opt=None):
        source = self._path(base_path) / module_path
        assert source.is_file(), f"module() names {source}, which does not exist"
        self.frozen[module_path] = source


def recorded_manifest():
    recorder = ManifestRecorder({"MPY_DIR": "/micropython", "PORT_DIR": "/micropython/ports/esp32"})
    recorder.run(FIRMWARE / "manifest.py")
    return recorder


def runtime_modules():
    return sorted(
        p.relative_to(ROOT).as_posix()
        for p in (ROOT / "openbricks").rglob("*.py")
        if "__pycache__" not in p.parts
    )


def test_the_image_freezes_every_runtime_module():
    frozen = recorded_manifest().frozen
    missing = [name for name in runtime_modules() if name not in frozen]
    assert not missing, f"not frozen into the image: {missing}"
    for name in runtime_modules():
        assert frozen[name] == ROOT / name


def test_the_startup_scripts_are_frozen_under_the_names_micropython_runs():
    frozen = recorded_manifest().frozen
    assert frozen["boot.py"] == FIRMWARE / "frozen" / "boot.py"
    assert frozen["main.py"] == FIRMWARE / "frozen" / "main.py"


def test_the_port_filesystem_setup_and_the_neopixel_driver_stay_in():
    recorder = recorded_manifest()
    assert ("$(PORT_DIR)/modules", None) in recorder.port_freezes  # _boot.py mounts the filesystem
    assert "neopixel" in recorder.requires  # hub.NeoPixelLED


# --- the boards ---------------------------------------------------------------------------------


def cmake_sets(path):
    """`set(NAME values...)` blocks of a CMake file as {NAME: [values]}."""
    text = re.sub(r"#.*", "", path.read_text())
    return {m.group(1): m.group(2).split() for m in re.finditer(r"set\(\s*(\w+)\s+([^)]*)\)", text)}


def header_defines(path):
    text = path.read_text()
    return {m.group(1): m.group(2).strip() for m in re.finditer(r"#define\s+(\w+)\s+(.+)", text)}


def sdkconfig(board):
    """The board's own sdkconfig fragments merged in build order (the port's base files excluded)."""
    values = {}
    for entry in cmake_sets(BOARDS / board / "mpconfigboard.cmake")["SDKCONFIG_DEFAULTS"]:
        if "${MICROPY_BOARD_DIR}" not in entry:
            continue
        path = Path(entry.replace("${MICROPY_BOARD_DIR}", str(BOARDS / board))).resolve()
        assert path.is_file(), f"{board} lists {path}, which does not exist"
        for line in path.read_text().splitlines():
            if "=" in line and not line.startswith("#"):
                key, value = line.split("=", 1)
                values[key.strip()] = value.strip()
    return values


@pytest.mark.parametrize("board", sorted(BOARD_CHIPS))
def test_boards_target_their_chip_and_use_the_shared_manifest(board):
    sets = cmake_sets(BOARDS / board / "mpconfigboard.cmake")
    assert sets["IDF_TARGET"] == [BOARD_CHIPS[board]]
    manifest = Path(sets["MICROPY_FROZEN_MANIFEST"][0].replace("${MICROPY_BOARD_DIR}", str(BOARDS / board)))
    assert manifest.resolve() == FIRMWARE / "manifest.py"


@pytest.mark.parametrize("board", sorted(BOARD_CHIPS))
def test_boards_have_ble_on(board):
    config = sdkconfig(board)
    assert config["CONFIG_BT_ENABLED"] == "y"
    assert config["CONFIG_BT_NIMBLE_ENABLED"] == "y"
    assert config["CONFIG_BT_BLUEDROID_ENABLED"] == "n"


@pytest.mark.parametrize("board", sorted(BOARD_CHIPS))
def test_boards_have_wifi_off(board):
    defines = header_defines(BOARDS / board / "mpconfigboard.h")
    assert defines["MICROPY_PY_NETWORK_WLAN"] == "(0)"
    assert defines["MICROPY_PY_ESPNOW"] == "(0)"
    assert sdkconfig(board)["CONFIG_ESP_COEX_SW_COEXIST_ENABLE"] == "n"


@pytest.mark.parametrize("board", sorted(BOARD_CHIPS))
def test_boards_keep_ringio_for_the_ble_bridge(board):
    assert header_defines(BOARDS / board / "mpconfigboard.h")["MICROPY_PY_MICROPYTHON_RINGIO"] == "(1)"


@pytest.mark.parametrize("board", sorted(BOARD_CHIPS))
def test_the_runtime_reads_the_right_chip_from_the_boards_machine_string(board):
    defines = header_defines(BOARDS / board / "mpconfigboard.h")
    machine = "{} with {}".format(
        defines["MICROPY_HW_BOARD_NAME"].strip('"'), defines["MICROPY_HW_MCU_NAME"].strip('"')
    )
    sys.path.insert(0, str(ROOT))
    try:
        from openbricks import pins
    finally:
        sys.path.remove(str(ROOT))
    had = hasattr(sys.implementation, "_machine")
    saved = getattr(sys.implementation, "_machine", None)
    sys.implementation._machine = machine
    try:
        pins.reset_claims()
        assert pins.chip() == BOARD_CHIPS[board]
    finally:
        if had:
            sys.implementation._machine = saved
        else:
            del sys.implementation._machine
        pins.reset_claims()


def test_s3_i2c0_is_the_gpio_maps_sensor_bus():
    defines = header_defines(BOARDS / "openbricks_esp32s3" / "mpconfigboard.h")
    assert (defines["MICROPY_HW_I2C0_SDA"], defines["MICROPY_HW_I2C0_SCL"]) == ("(15)", "(16)")


def test_s3_uses_its_8mb_flash_and_native_usb():
    config = sdkconfig("openbricks_esp32s3")
    assert config["CONFIG_ESPTOOLPY_FLASHSIZE_8MB"] == "y"
    # MicroPython 1.28's port turns native USB on for every chip with a USB-OTG peripheral (there is
    # no sdkconfig.usb fragment any more); the board must not switch it off.
    assert "MICROPY_HW_ENABLE_USBDEV" not in header_defines(BOARDS / "openbricks_esp32s3" / "mpconfigboard.h")


def test_the_classic_esp32s_controller_options_stay_with_the_classic_esp32():
    """BTDM_CTRL_* exist only for the classic ESP32: from the shared fragment, the S3 build dropped them."""
    shared = (BOARDS / "sdkconfig.ble").read_text()
    assert "CONFIG_BTDM_" not in re.sub(r"#.*", "", shared)
    assert sdkconfig("openbricks_esp32")["CONFIG_BTDM_CTRL_MODE_BLE_ONLY"] == "y"


# --- the build script ---------------------------------------------------------------------------


def run_build(args, env_extra=None, path_prefix=None):
    env = {k: v for k, v in os.environ.items() if k not in ("IDF_PATH", "MICROPY_DIR")}
    env.update(env_extra or {})
    if path_prefix is not None:
        env["PATH"] = f"{path_prefix}:{env['PATH']}"
    return subprocess.run(
        ["bash", str(BUILD_SCRIPT), *args], capture_output=True, text=True, env=env, timeout=60
    )


def fake_micropython(tmp_path, submodules=True):
    mp = tmp_path / "micropython"
    (mp / "py").mkdir(parents=True)
    (mp / "py" / "mpconfig.h").write_text("")
    (mp / "ports" / "esp32").mkdir(parents=True)
    (mp / "ports" / "esp32" / "Makefile").write_text("")
    (mp / "mpy-cross").mkdir()
    if submodules:
        (mp / "lib" / "micropython-lib" / "micropython").mkdir(parents=True)
    return mp


def fake_idf(tmp_path, major=5, minor=5):
    idf = tmp_path / "esp-idf"
    (idf / "tools" / "cmake").mkdir(parents=True)
    (idf / "tools" / "cmake" / "version.cmake").write_text(
        f"set(IDF_VERSION_MAJOR {major})\nset(IDF_VERSION_MINOR {minor})\nset(IDF_VERSION_PATCH 4)\n"
    )
    return idf


def fake_tools(tmp_path, with_idf_py=True):
    """`make` that logs its arguments and produces firmware.bin for a port build; `idf.py` that exists."""
    bin_dir = tmp_path / "bin"
    bin_dir.mkdir()
    log = tmp_path / "make.log"
    make = bin_dir / "make"
    make.write_text(
        textwrap.dedent(
            f"""\
            #!/usr/bin/env bash
            echo "$*" >> {log}
            if [[ $2 == */ports/esp32 ]]; then
                for arg in "$@"; do
                    case $arg in BOARD=*) board=${{arg#BOARD=}} ;; esac
                done
                mkdir -p "$2/build-$board" && echo image > "$2/build-$board/firmware.bin"
            fi
            """
        )
    )
    make.chmod(0o755)
    if with_idf_py:
        idf_py = bin_dir / "idf.py"
        idf_py.write_text("#!/bin/sh\nexit 0\n")
        idf_py.chmod(0o755)
    return bin_dir, log


def test_build_without_a_target_prints_usage():
    result = run_build([])
    assert result.returncode == 2
    assert "build_firmware.sh esp32s3 [MICROPYTHON_DIR]" in result.stderr


def test_build_rejects_an_unknown_target():
    result = run_build(["esp32c3"])
    assert result.returncode == 1
    assert "unknown target 'esp32c3': use esp32 or esp32s3" in result.stderr


def test_build_without_micropython_says_where_to_point_it(tmp_path):
    result = run_build(["esp32s3"], {"IDF_PATH": str(fake_idf(tmp_path))})
    assert result.returncode == 1
    assert "no MicroPython checkout given" in result.stderr
    assert "MICROPY_DIR" in result.stderr


def test_build_with_a_missing_micropython_dir(tmp_path):
    result = run_build(["esp32s3", str(tmp_path / "nope")])
    assert result.returncode == 1
    assert "does not exist" in result.stderr


def test_build_with_a_dir_that_is_not_micropython(tmp_path):
    result = run_build(["esp32", str(tmp_path)])
    assert result.returncode == 1
    assert "is not a MicroPython checkout" in result.stderr


def test_build_without_micropython_submodules_says_how_to_fetch_them(tmp_path):
    mp = fake_micropython(tmp_path, submodules=False)
    result = run_build(["esp32s3"], {"MICROPY_DIR": str(mp)})
    assert result.returncode == 1
    assert f"make -C {mp}/ports/esp32 submodules" in result.stderr


def test_build_without_idf_path_says_to_source_export_sh(tmp_path):
    mp = fake_micropython(tmp_path)
    result = run_build(["esp32s3", str(mp)])
    assert result.returncode == 1
    assert "IDF_PATH is not set" in result.stderr
    assert "export.sh" in result.stderr


def test_build_refuses_an_esp_idf_that_is_too_old(tmp_path):
    mp = fake_micropython(tmp_path)
    result = run_build(["esp32s3", str(mp)], {"IDF_PATH": str(fake_idf(tmp_path, 5, 1))})
    assert result.returncode == 1
    assert "ESP-IDF v5.1 found" in result.stderr
    assert "v5.3-v5.5" in result.stderr


def test_build_without_idf_py_on_path(tmp_path):
    mp = fake_micropython(tmp_path)
    bin_dir, _log = fake_tools(tmp_path, with_idf_py=False)
    env = {"IDF_PATH": str(fake_idf(tmp_path))}
    result = run_build(["esp32s3", str(mp)], env, path_prefix=bin_dir)
    if result.returncode == 0:
        pytest.fail("idf.py is on this machine's PATH, so its absence cannot be simulated")
    assert "idf.py is not on PATH" in result.stderr


@pytest.mark.parametrize("target", ["esp32", "esp32s3"])
def test_build_makes_mpy_cross_then_the_board_with_our_c_module(tmp_path, target):
    mp = fake_micropython(tmp_path)
    bin_dir, log = fake_tools(tmp_path)
    result = run_build([target], {"IDF_PATH": str(fake_idf(tmp_path)), "MICROPY_DIR": str(mp)}, bin_dir)
    assert result.returncode == 0, result.stderr
    calls = log.read_text().splitlines()
    assert len(calls) == 2
    assert calls[0].startswith(f"-C {mp}/mpy-cross")
    port_call = calls[1].split()
    assert port_call[:2] == ["-C", f"{mp}/ports/esp32"]
    args = dict(a.split("=", 1) for a in port_call if "=" in a)
    assert args["BOARD"] == "openbricks_" + target
    assert Path(args["BOARD_DIR"]) == BOARDS / ("openbricks_" + target)
    modules = Path(args["USER_C_MODULES"])
    assert modules == FIRMWARE / "native" / "user_c_modules" / "micropython.cmake" and modules.is_file()
    image = mp / "ports" / "esp32" / ("build-openbricks_" + target) / "firmware.bin"
    assert str(image) in result.stdout


# --- mpy-cross ----------------------------------------------------------------------------------


def mpy_cross(source, out_dir):
    out = out_dir / (source.stem + ".mpy")
    result = subprocess.run(
        [sys.executable, "-m", "mpy_cross", "-march=xtensawin", "-o", str(out), str(source)],
        capture_output=True,
        text=True,
        timeout=60,
    )
    return result, out


@pytest.mark.parametrize("script", ["boot.py", "main.py"])
def test_the_startup_scripts_compile_with_mpy_cross(tmp_path, script):
    result, out = mpy_cross(FIRMWARE / "frozen" / script, tmp_path)
    assert result.returncode == 0, result.stderr
    assert out.read_bytes()[:1] == b"M"


def test_every_frozen_runtime_module_compiles_with_mpy_cross(tmp_path):
    failures = []
    for name, source in sorted(recorded_manifest().frozen.items()):
        result, _out = mpy_cross(source, tmp_path)
        if result.returncode != 0:
            failures.append(f"{name}: {result.stderr.strip()}")
    assert not failures, "the image build would stop here:\n" + "\n".join(failures)


# --- the frozen main.py, run with the hardware fakes --------------------------------------------

MAIN_HARNESS = """
import builtins, sys, traceback
sys.path[:0] = [{root!r}, {fakes!r}]
# MicroPython's sys.print_exception, which CPython lacks.
sys.print_exception = lambda exc, file=sys.stderr: traceback.print_exception(exc, file=file)
import fakes
fakes.install()
fakes.reset()
import esp32
from machine import board
from fakes import bluetooth as radio
from openbricks import launcher, pins

pins.set_chip({chip!r})
nvs = esp32.NVS("openbricks")
nvs.set_blob("hub_name", b"RobotA")
nvs.commit()

user_main = {user_main!r}
real_open = builtins.open

def hub_open(path, *args, **kwargs):
    if path == "/main.py":
        if user_main is None:
            raise OSError(2, "no /main.py")
        path = user_main
    return real_open(path, *args, **kwargs)

builtins.open = hub_open

def fake_run(*args, **kwargs):
    leds = [data for pin, _timing, data in board.bitstreams if pin == 48]
    print("launcher.run called")
    print("advertising:", radio.advertised_name())
    print("s3 led:", tuple(leds[-1]) if leds else None)
    print("gpio2:", board.pins[2].value() if 2 in board.pins else None)

launcher.run = fake_run
source = real_open({main!r}).read()
exec(compile(source, "main.py", "exec"), {{"__name__": "__main__"}})
"""


def run_frozen_main(tmp_path, chip, user_main=None):
    script = MAIN_HARNESS.format(
        root=str(ROOT),
        fakes=str(ROOT / "tests" / "openbricks"),
        chip=chip,
        user_main=user_main,
        main=str(FIRMWARE / "frozen" / "main.py"),
    )
    return subprocess.run(
        [sys.executable, "-c", script], capture_output=True, text=True, timeout=60, cwd=tmp_path
    )


def test_frozen_main_wires_the_s3_hub_and_starts_the_launcher(tmp_path):
    result = run_frozen_main(tmp_path, "esp32s3")
    assert result.returncode == 0, result.stderr
    assert "launcher.run called" in result.stdout
    assert "advertising: RobotA" in result.stdout
    assert "s3 led: (0, 0, 51)" in result.stdout  # GRB: blue at 0.2 brightness, BLE on


def test_frozen_main_wires_the_classic_hub(tmp_path):
    result = run_frozen_main(tmp_path, "esp32")
    assert result.returncode == 0, result.stderr
    assert "advertising: RobotA" in result.stdout
    assert "gpio2: 0" in result.stdout  # single-colour LED dark at idle
    assert "launcher.run called" in result.stdout


def test_frozen_main_still_starts_the_launcher_when_the_hub_fails(tmp_path):
    result = run_frozen_main(tmp_path, None)  # no chip recognised: no hub to wire
    assert result.returncode == 0, result.stderr
    assert "construct ESP32DevkitHub() or ESP32S3DevkitHub() explicitly" in result.stderr
    assert "launcher.run called" in result.stdout


def test_a_user_main_py_replaces_the_frozen_one(tmp_path):
    user = tmp_path / "user_main.py"
    user.write_text("print('user main ran as', __name__)\n")
    result = run_frozen_main(tmp_path, "esp32s3", str(user))
    assert result.returncode == 0, result.stderr
    assert "user main ran as __main__" in result.stdout
    assert "launcher.run called" not in result.stdout
    assert "advertising" not in result.stdout
