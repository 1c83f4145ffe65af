# openbricks ESP32-S3 hub (ESP32-S3 DevKitC-1, 8 MB flash). Built out of tree:
#   make -C <micropython>/ports/esp32 BOARD=openbricks_esp32s3 BOARD_DIR=<this folder> \
#        USER_C_MODULES=<repo>/firmware/native/user_c_modules/micropython.cmake
# (firmware/build_firmware.sh does exactly that).
set(IDF_TARGET esp32s3)

set(SDKCONFIG_DEFAULTS
    boards/sdkconfig.base
    ${MICROPY_BOARD_DIR}/../sdkconfig.ble
    ${MICROPY_BOARD_DIR}/../sdkconfig.nowifi
    ${MICROPY_BOARD_DIR}/sdkconfig.board
)

set(MICROPY_FROZEN_MANIFEST ${MICROPY_BOARD_DIR}/../../manifest.py)
