/*
 * The hub's UART as the serial-bus engine's wire (uart.h), on ESP-IDF's UART driver.
 *
 * Only this file knows the peripheral. The engine's tick calls these four
 * functions and nothing else, and none of them calls Python, so the engine can
 * run on the hard tick. The direction pin of a half-duplex adapter is driven
 * by the driver itself (UART_MODE_RS485_HALF_DUPLEX puts RTS on it).
 * It cannot be compiled without ESP-IDF; keep it this small.
 */
#if defined(ESP_PLATFORM)

#include "driver/uart.h"
#include "esp_timer.h"
#include "freertos/FreeRTOS.h"
#include "mp_bindings.h"

#define RX_BUFFER_BYTES 512

static ob_uart_t wires[UART_NUM_MAX];
static uart_port_t ports[UART_NUM_MAX];

static bool esp_write(void *ctx, const uint8_t *data, size_t n) {
    uart_port_t port = *(uart_port_t *)ctx;
    return uart_write_bytes(port, data, n) == (int)n;
}

static size_t esp_read(void *ctx, uint8_t *buf, size_t cap, uint32_t timeout_us) {
    uart_port_t port = *(uart_port_t *)ctx;
    TickType_t ticks = pdMS_TO_TICKS((timeout_us + 999u) / 1000u);
    int n = uart_read_bytes(port, buf, (uint32_t)cap, ticks > 0 ? ticks : 1);
    return n > 0 ? (size_t)n : 0u;
}

static void esp_flush_input(void *ctx) {
    uart_flush_input(*(uart_port_t *)ctx);
}

static uint32_t esp_now_us(void *ctx) {
    (void)ctx;
    return (uint32_t)esp_timer_get_time();
}

const ob_uart_t *ob_mp_uart_esp32_open(int uart_id, mp_obj_t tx, mp_obj_t rx, uint32_t baud, mp_obj_t dir_pin) {
    if (uart_id < 0 || uart_id >= UART_NUM_MAX || tx == mp_const_none || rx == mp_const_none) {
        mp_raise_ValueError(MP_ERROR_TEXT("serial_bus(): give a UART id of this chip and its tx and rx pins"));
    }
    uart_port_t port = (uart_port_t)uart_id;
    if (uart_is_driver_installed(port)) {
        uart_driver_delete(port); /* a previous program's engine, or machine.UART's leftover */
    }
    uart_config_t config = {
        .baud_rate = (int)baud,
        .data_bits = UART_DATA_8_BITS,
        .parity = UART_PARITY_DISABLE,
        .stop_bits = UART_STOP_BITS_1,
        .flow_ctrl = UART_HW_FLOWCTRL_DISABLE,
        .source_clk = UART_SCLK_DEFAULT,
    };
    int rts = dir_pin == mp_const_none ? UART_PIN_NO_CHANGE : mp_obj_get_int(dir_pin);
    if (uart_driver_install(port, RX_BUFFER_BYTES, 0, 0, NULL, 0) != ESP_OK ||
        uart_param_config(port, &config) != ESP_OK ||
        uart_set_pin(port, mp_obj_get_int(tx), mp_obj_get_int(rx), rts, UART_PIN_NO_CHANGE) != ESP_OK ||
        (dir_pin != mp_const_none && uart_set_mode(port, UART_MODE_RS485_HALF_DUPLEX) != ESP_OK)) {
        mp_raise_msg_varg(&mp_type_OSError, MP_ERROR_TEXT("serial_bus(): UART%d could not be set up"), uart_id);
    }
    ports[port] = port;
    wires[port] = (ob_uart_t){esp_write, esp_read, esp_flush_input, esp_now_us, &ports[port]};
    return &wires[port];
}

#endif /* ESP_PLATFORM */
