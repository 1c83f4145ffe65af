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
}

void ob_hard_tick_fire(ob_hard_tick_t *tick) {
    tick->count = tick->count + 1u;
    ob_hard_tick_work_fn_t work = tick->work;
    if (work == NULL) {
        return;
    }
    if (!ob_hard_timer_try_lock()) {
        tick->contended = tick->contended + 1u;
        return;
    }
    if (work(tick->work_ctx)) {
        tick->dispatched = tick->dispatched + 1u;
    }
    ob_hard_timer_unlock();
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
