/*
 * The hard tick's count and self-test verdict (see hard_tick.h).
 */
#include "hard_tick.h"

#include <stddef.h>

#include "hard_timer.h"

void ob_hard_tick_init(ob_hard_tick_t *tick) {
    tick->count = 0;
    tick->dispatched = 0;
    tick->contended = 0;
    tick->running = false;
    tick->work = NULL;
    tick->work_ctx = NULL;
    tick->n_polls = 0;
}

void ob_hard_tick_fire(ob_hard_tick_t *tick) {
    tick->count = tick->count + 1u;
    ob_hard_tick_work_fn_t work = tick->work;
    if (work == NULL && tick->n_polls == 0u) {
        return;
    }
    if (!ob_hard_timer_try_lock()) {
        tick->contended = tick->contended + 1u;
        return;
    }
    for (uint32_t i = 0; i < tick->n_polls; i++) {
        tick->poll_fn[i](tick->poll_ctx[i]);
    }
    if (work != NULL && work(tick->work_ctx)) {
        tick->dispatched = tick->dispatched + 1u;
    }
    ob_hard_timer_unlock();
}

bool ob_hard_tick_add_poll(ob_hard_tick_t *tick, ob_hard_tick_poll_fn_t fn, void *ctx) {
    uint32_t n = tick->n_polls;
    for (uint32_t i = 0; i < n; i++) {
        if (tick->poll_ctx[i] == ctx) {
            tick->poll_fn[i] = fn;
            return true;
        }
    }
    if (n >= OB_HARD_TICK_MAX_POLLS) {
        return false;
    }
    tick->poll_fn[n] = fn;
    tick->poll_ctx[n] = ctx;
    tick->n_polls = n + 1u;
    return true;
}

void ob_hard_tick_remove_poll(ob_hard_tick_t *tick, void *ctx) {
    uint32_t n = tick->n_polls;
    for (uint32_t i = 0; i < n; i++) {
        if (tick->poll_ctx[i] == ctx) {
            /* Keep the order: later sensors move down one place. */
            for (uint32_t j = i + 1u; j < n; j++) {
                tick->poll_fn[j - 1u] = tick->poll_fn[j];
                tick->poll_ctx[j - 1u] = tick->poll_ctx[j];
            }
            tick->n_polls = n - 1u;
            return;
        }
    }
}

uint32_t ob_hard_tick_expected(uint32_t elapsed_us) {
    return elapsed_us / OB_HARD_TICK_PERIOD_US;
}

bool ob_hard_tick_rate_ok(uint32_t ticks, uint32_t elapsed_us) {
    uint32_t expected = ob_hard_tick_expected(elapsed_us);
    if (expected == 0u) {
        return false;
    }
    uint64_t low = (uint64_t)expected * OB_HARD_TICK_MIN_SHARE_PCT;
    uint64_t high = (uint64_t)expected * 100u * 100u / OB_HARD_TICK_MIN_SHARE_PCT;
    uint64_t got = (uint64_t)ticks * 100u;
    return got >= low && got <= high;
}
