/*
 * The platform's 1 kHz timer behind the hard tick (hard_tick.h), and the lock
 * that keeps its callback and the interpreter off the controllers at once.
 *
 * Implementations: platform/hard_timer_posix.c (a thread on host builds: the
 * unix MicroPython and the CPython extension) and the hub's esp_timer glue
 * (user_c_modules/openbricks/mp_hard_timer_esp32.c). The callback runs in the
 * timer's own context: it must not allocate, block or call the interpreter.
 */
#ifndef OB_HARD_TIMER_H
#define OB_HARD_TIMER_H

#include <stdbool.h>
#include <stdint.h>

typedef void (*ob_hard_timer_fn_t)(void *ctx);

/* Call fn(ctx) every period_us from now on; false if the timer could not start. Idempotent. */
bool ob_hard_timer_start(ob_hard_timer_fn_t fn, void *ctx, uint32_t period_us);

/* The platform's monotonic microsecond clock (wraps modulo 2^32). */
uint32_t ob_hard_timer_now_us(void);

/* Sleep (or yield) for about ms milliseconds outside the timer's context. */
void ob_hard_timer_sleep_ms(uint32_t ms);

/*
 * The motor lock: the timer's callback and the interpreter never work on the
 * controllers at the same time. The interpreter takes it (blocking, and
 * recursively: a locked call may reach another) around each call into a
 * controller the hard tick runs; the timer only tries it and skips its
 * period when the interpreter holds it (the clock is measured, so a skipped
 * period costs one control update, never trajectory time).
 */
void ob_hard_timer_lock(void);
bool ob_hard_timer_try_lock(void);
void ob_hard_timer_unlock(void);

#endif /* OB_HARD_TIMER_H */
