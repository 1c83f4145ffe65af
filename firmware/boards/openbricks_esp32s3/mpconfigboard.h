// openbricks ESP32-S3 hub (ESP32-S3 DevKitC-1).
//
// The machine string (sys.implementation._machine) is "<board name> with <MCU name>"; the runtime
// reads the chip from its tail (openbricks.pins), so the MCU name must stay "ESP32S3".
#define MICROPY_HW_BOARD_NAME               "openbricks ESP32-S3 hub"
#define MICROPY_HW_MCU_NAME                 "ESP32S3"

// The DevKitC-1's USB-UART port keeps a REPL next to the native USB one.
#define MICROPY_HW_ENABLE_UART_REPL         (1)

// I2C0 on the GPIO map's sensor bus (SDA 15, SCL 16), so a bare machine.I2C(0) is the right bus.
#define MICROPY_HW_I2C0_SCL                 (16)
#define MICROPY_HW_I2C0_SDA                 (15)

// WiFi off: BLE is the hub's only radio (see ../sdkconfig.nowifi).
#define MICROPY_PY_NETWORK_WLAN             (0)
#define MICROPY_PY_ESPNOW                   (0)

// micropython.RingIO: the BLE REPL bridge's fixed input/output rings.
#define MICROPY_PY_MICROPYTHON_RINGIO       (1)
