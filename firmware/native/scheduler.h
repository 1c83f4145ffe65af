/*
 * Subscriber registry and tick dispatch of the always-on control tick
 * (pbio motor_process.c in spirit).
 *
 * The clock is measured, not counted: each tick is given the current time,
 * and subscribers see that time. A late or dropped tick costs control
 * updates, never trajectory time.
 */
#ifndef OB_SCHEDULER_H
#define OB_SCHEDULER_H

#include <stdbool.h>
#include <stdint.h>

#define OB_SCHEDULER_MAX_SUBSCRIBERS 16

/* A native subscriber: called once per tick with the scheduler clock. */
typedef void (*ob_tick_fn_t)(void *ctx, uint32_t now_ms);

typedef struct {
    ob_tick_fn_t fn;
    void *ctx;
} ob_subscriber_t;

typedef struct {
    ob_subscriber_t subscribers[OB_SCHEDULER_MAX_SUBSCRIBERS];
    int count;
    bool started;
    uint32_t now_ms;       /* clock as of the last tick */
    uint32_t last_dt_ms;   /* measured spacing of the last two ticks */
    uint32_t tick_count;   /* ticks dispatched */
    uint32_t late_ticks;   /* ticks that arrived more than 1 ms after the previous one */
} ob_scheduler_t;

void ob_scheduler_init(ob_scheduler_t *s);

/* Register fn/ctx; idempotent for the same pair. Returns false when full. */
bool ob_scheduler_subscribe(ob_scheduler_t *s, ob_tick_fn_t fn, void *ctx);

/* Remove fn/ctx if registered; order of the others is kept. */
void ob_scheduler_unsubscribe(ob_scheduler_t *s, ob_tick_fn_t fn, void *ctx);

bool ob_scheduler_is_subscribed(const ob_scheduler_t *s, ob_tick_fn_t fn, void *ctx);

/* Advance the clock to now_ms (measured; wraps modulo 2^32) and call every subscriber. */
void ob_scheduler_tick(ob_scheduler_t *s, uint32_t now_ms);

#endif /* OB_SCHEDULER_H */
