/*
 * The pulse counter a quadrature encoder is read from: one PCNT unit.
 *
 * The encoder core (encoder.c) never touches a peripheral. Whoever owns the
 * counter fills in `read`:
 *
 *   - the hub: ESP-IDF's pulse_cnt driver (user_c_modules/openbricks/mp_pcnt_esp32.c),
 *     a unit counting both edges of both channels (x4) between -OB_PCNT_LIMIT
 *     and +OB_PCNT_LIMIT;
 *   - the tests: a counter model fed through the bindings' sample(raw).
 *
 * A PCNT unit's counter is 16 bits wide and returns to 0 when it reaches
 * either limit, so what it reads repeats every OB_PCNT_LIMIT counts: the
 * encoder core unwraps it, which is right as long as it is read at least
 * once per OB_PCNT_LIMIT / 2 counts (the hard tick reads it every
 * millisecond: 16 million counts per second of headroom).
 *
 * Rules for an implementation: `read` runs inside the 1 kHz tick, so it never
 * allocates, blocks or calls the interpreter.
 */
#ifndef OB_PCNT_H
#define OB_PCNT_H

#include <stdbool.h>
#include <stdint.h>

/* The limits the hub configures (the widest symmetric pair a 16-bit counter holds). */
#define OB_PCNT_LIMIT 32767

/* The manual's pcnt_filter: the glitch filter in 80 MHz APB cycles, at most this (~12.8 us). */
#define OB_PCNT_FILTER_MAX_CYCLES 1023

typedef struct {
    /* The counter's current value into *raw; false when it could not be read. */
    bool (*read)(void *ctx, int32_t *raw);
    void *ctx;
} ob_pcnt_t;

#endif /* OB_PCNT_H */
