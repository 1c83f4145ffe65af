/*
 * The byte wire the serial-bus engine talks through: one half-duplex UART.
 *
 * The engine (serial_bus.c) never touches a peripheral. Whoever owns the
 * wire fills in these four functions:
 *
 *   - the hub: ESP-IDF's UART driver (user_c_modules/openbricks/mp_uart_esp32.c);
 *   - the simulator: its emulated bus, with the byte timing of a real 1 Mbaud
 *     half-duplex line (sim/native/scs_wire.c);
 *   - the tests and the unix port: a Python object with write(bytes) and
 *     read() (the bindings' adapters), in front of scripted servos.
 *
 * Rules for an implementation: the functions run inside the 1 kHz tick, so
 * they never allocate and never wait longer than they are told to.
 */
#ifndef OB_UART_H
#define OB_UART_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

typedef struct {
    /* Send n bytes (returns when they are queued or on the wire); false if the UART refused them. */
    bool (*write)(void *ctx, const uint8_t *data, size_t n);
    /*
     * Up to cap received bytes; waits at most timeout_us for the first one.
     * Returns how many were stored (0: nothing arrived in time).
     */
    size_t (*read)(void *ctx, uint8_t *buf, size_t cap, uint32_t timeout_us);
    /* Drop whatever was received and not read yet (a late reply to an earlier request). */
    void (*flush_input)(void *ctx);
    /* The wire's microsecond clock (wraps modulo 2^32): what deadlines and bus time are measured on. */
    uint32_t (*now_us)(void *ctx);
    void *ctx;
} ob_uart_t;

/* Microseconds one byte (start + 8 data + stop bits) occupies the line at baud. */
static inline uint32_t ob_uart_byte_us(uint32_t baud) {
    return baud == 0u ? 0u : (10000000u + baud - 1u) / baud;
}

#endif /* OB_UART_H */
