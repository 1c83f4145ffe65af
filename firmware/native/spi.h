/*
 * The SPI link a register-mapped sensor is read through: one device, its chip
 * select handled by the link.
 *
 * The sensor cores (icm45686.c) never touch a peripheral. Whoever owns the
 * bus fills in these functions:
 *
 *   - the hub: ESP-IDF's spi_master driver (user_c_modules/openbricks/mp_spi_esp32.c);
 *   - the tests and host builds: a Python transfer(bytes) -> bytes in front of a
 *     register model of the chip (the bindings' adapters).
 *
 * Rules for an implementation: `transfer` may run inside the 1 kHz tick, so
 * it never allocates and finishes in microseconds (a 13-byte burst at 8 MHz
 * is 13 us); `delay_ms` is only called while a sensor is being set up,
 * outside the tick.
 */
#ifndef OB_SPI_H
#define OB_SPI_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

typedef struct {
    /* One chip-select window: clock out tx[0..n), store what came back in rx[0..n). False on failure. */
    bool (*transfer)(void *ctx, const uint8_t *tx, uint8_t *rx, size_t n);
    /* Wait about ms milliseconds (setup only). */
    void (*delay_ms)(void *ctx, uint32_t ms);
    void *ctx;
} ob_spi_t;

#endif /* OB_SPI_H */
