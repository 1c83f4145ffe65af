// openbricks ESP32 hub (ESP32 DevKitC-V4).
//
// The machine string (sys.implementation._machine) is "<board name> with <MCU name>"; the runtime
// reads the chip from its tail (openbricks.pins), so the MCU name must stay "ESP32".
#define MICROPY_HW_BOARD_NAME               "openbricks ESP32 hub"
#define MICROPY_HW_MCU_NAME                 "ESP32"

// I2C0 on the classic ESP32's usual pins (SDA 21, SCL 22), so a bare machine.I2C(0) is that bus.
#define MICROPY_HW_I2C0_SCL                 (22)
#define MICROPY_HW_I2C0_SDA                 (21)

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
