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

// Raw-paste window = half of this. MicroPython's default (256 -> a 128-byte window) caps a BLE upload
// near a sixth of the link: each window costs a round trip of two connection intervals. 4096 grants
// 2 KB windows, which keeps the link busy; the BLE bridge's RX buffer (ble_repl.RX_BUFFER_BYTES)
// holds two windows in flight. `openbricks paste-probe` measures what a hub really survives.
#define MICROPY_REPL_STDIN_BUFFER_MAX       (4096)
