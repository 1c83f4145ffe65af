#!/usr/bin/env bash
# Build an openbricks firmware image.
#
#   firmware/build_firmware.sh esp32s3 [MICROPYTHON_DIR]     # ESP32-S3 DevKitC-1
#   firmware/build_firmware.sh esp32   [MICROPYTHON_DIR]     # classic ESP32 DevKitC-V4
#
# MicroPython is not part of this repository: pass the path of a checkout (v1.27 or newer, with its
# submodules) as the second argument or in $MICROPY_DIR. ESP-IDF v5.3-v5.5 must be set up in this
# shell: $IDF_PATH set and idf.py on PATH, which `. <esp-idf>/export.sh` does.
#
# Builds mpy-cross, then the board from firmware/boards/ with our C control cores as a user C module
# and the openbricks package frozen in. The image lands in
# <micropython>/ports/esp32/build-openbricks_<target>/firmware.bin.
set -euo pipefail

die() {
    echo "build_firmware.sh: error: $*" >&2
    exit 1
}

usage() {
    sed -n '2,13p' "${BASH_SOURCE[0]}" | sed 's/^# \{0,1\}//'
}

if [[ $# -lt 1 ]]; then
    usage >&2
    exit 2
fi
case "$1" in
    esp32 | esp32s3) target=$1 ;;
    -h | --help)
        usage
        exit 0
        ;;
    *) die "unknown target '$1': use esp32 or esp32s3" ;;
esac

repo=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
board=openbricks_$target
board_dir=$repo/firmware/boards/$board
user_c_modules=$repo/firmware/native/user_c_modules/micropython.cmake
[[ -f $board_dir/mpconfigboard.cmake ]] || die "board definition $board_dir is missing"
[[ -f $user_c_modules ]] || die "the C module definition $user_c_modules is missing"

# --- MicroPython --------------------------------------------------------------------------------
micropython=${2:-${MICROPY_DIR:-}}
[[ -n $micropython ]] ||
    die "no MicroPython checkout given: pass its path as the second argument or set MICROPY_DIR (MicroPython v1.27 or newer)"
[[ -d $micropython ]] || die "MicroPython checkout '$micropython' does not exist"
micropython=$(cd "$micropython" && pwd)
[[ -f $micropython/py/mpconfig.h && -f $micropython/ports/esp32/Makefile && -d $micropython/mpy-cross ]] ||
    die "'$micropython' is not a MicroPython checkout (expected py/mpconfig.h, ports/esp32/ and mpy-cross/)"
[[ -d $micropython/lib/micropython-lib/micropython ]] ||
    die "MicroPython's submodules are missing (lib/micropython-lib is empty): run 'make -C $micropython/ports/esp32 submodules'"

# --- ESP-IDF ------------------------------------------------------------------------------------
[[ -n ${IDF_PATH:-} ]] ||
    die "IDF_PATH is not set: install ESP-IDF v5.3-v5.5 (v5.5.4 recommended) and run '. <esp-idf>/export.sh' in this shell"
[[ -d $IDF_PATH ]] || die "IDF_PATH points to '$IDF_PATH', which does not exist"
version_file=$IDF_PATH/tools/cmake/version.cmake
[[ -f $version_file ]] || die "IDF_PATH '$IDF_PATH' is not an ESP-IDF tree (no tools/cmake/version.cmake)"
idf_major=$(sed -n 's/^ *set *( *IDF_VERSION_MAJOR *\([0-9]*\) *).*/\1/p' "$version_file")
idf_minor=$(sed -n 's/^ *set *( *IDF_VERSION_MINOR *\([0-9]*\) *).*/\1/p' "$version_file")
[[ -n $idf_major && -n $idf_minor ]] || die "cannot read the ESP-IDF version from $version_file"
if ((idf_major < 5 || (idf_major == 5 && idf_minor < 3))); then
    die "ESP-IDF v$idf_major.$idf_minor found at $IDF_PATH; openbricks needs v5.3-v5.5 (v5.5.4 recommended)"
fi
if ((idf_major > 5 || idf_minor > 5)); then
    echo "build_firmware.sh: warning: ESP-IDF v$idf_major.$idf_minor is newer than the tested v5.3-v5.5" >&2
fi
command -v idf.py >/dev/null ||
    die "idf.py is not on PATH: run '. $IDF_PATH/export.sh' in this shell"

# --- build --------------------------------------------------------------------------------------
jobs=$(nproc 2>/dev/null || echo 2)

echo "==> mpy-cross"
make -C "$micropython/mpy-cross" -j"$jobs"

echo "==> $board (ESP-IDF v$idf_major.$idf_minor)"
make -C "$micropython/ports/esp32" -j"$jobs" \
    BOARD="$board" \
    BOARD_DIR="$board_dir" \
    USER_C_MODULES="$user_c_modules"

image=$micropython/ports/esp32/build-$board/firmware.bin
[[ -f $image ]] || die "the build finished without producing $image"
echo "==> $image"
echo "flash it with: openbricks flash --name NAME --firmware $image"
