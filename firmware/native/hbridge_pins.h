/*
 * The pins one H-bridge channel is driven through: two direction inputs
 * (IN1, IN2) and a PWM on its enable input (EN), as on an L298N or a TB6612.
 *
 * The H-bridge core (hbridge.c) never touches a peripheral. Whoever owns the
 * pins fills in `write` and `duty_max`:
 *
 *   - the hub: GPIO for IN1/IN2 and an LEDC channel for EN
 *     (user_c_modules/openbricks/mp_hbridge_esp32.c);
 *   - the unix port's tests: an emulated DC motor with its encoder, in C
 *     (user_c_modules/openbricks_bench/), which turns as the levels say;
 *   - nothing (write NULL): the core only keeps the levels, for host tests.
 *
 * Rules for an implementation: `write` runs inside the 1 kHz tick, so it
 * never allocates, blocks or calls the interpreter. When it drops EN to 0 it
 * does so before changing IN1/IN2, and raises EN only after them, so a
 * reversal never passes through a full-duty glitch of the old direction.
 */
#ifndef OB_HBRIDGE_PINS_H
#define OB_HBRIDGE_PINS_H

#include <stdbool.h>
#include <stdint.h>

typedef struct {
    /* IN1 and IN2 to in1/in2, EN's PWM to duty out of duty_max; false when the hardware refused. */
    bool (*write)(void *ctx, bool in1, bool in2, uint32_t duty);
    uint32_t duty_max; /* the duty that holds EN high the whole period (LEDC: 2^resolution) */
    void *ctx;
} ob_hbridge_pins_t;

#endif /* OB_HBRIDGE_PINS_H */
