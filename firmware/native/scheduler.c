/*
 * The always-on control tick's registry and dispatch.
 *
 * Subscribers are kept in registration order so the order of a control
 * period is predictable (a drivebase registered before its wheels runs
 * before them). A subscriber may subscribe or unsubscribe others, or itself,
 * from inside its tick: the round works on a snapshot of the registry taken
 * when the tick starts, and skips entries removed since, so a removed
 * subscriber is never called after its removal and a new one first runs on
 * the next tick.
 */
#include "scheduler.h"

#include <string.h>

static int find(const ob_scheduler_t *s, ob_tick_fn_t fn, const void *ctx) {
    for (int i = 0; i < s->count; i++) {
        if (s->subscribers[i].fn == fn && s->subscribers[i].ctx == ctx) {
            return i;
        }
    }
    return -1;
}

void ob_scheduler_init(ob_scheduler_t *s) {
    memset(s, 0, sizeof(*s));
}

bool ob_scheduler_subscribe(ob_scheduler_t *s, ob_tick_fn_t fn, void *ctx) {
    if (fn == NULL) {
        return false;
    }
    if (find(s, fn, ctx) >= 0) {
        return true;
    }
    if (s->count >= OB_SCHEDULER_MAX_SUBSCRIBERS) {
        return false;
    }
    s->subscribers[s->count].fn = fn;
    s->subscribers[s->count].ctx = ctx;
    s->count++;
    return true;
}

void ob_scheduler_unsubscribe(ob_scheduler_t *s, ob_tick_fn_t fn, void *ctx) {
    int i = find(s, fn, ctx);
    if (i < 0) {
        return;
    }
    memmove(&s->subscribers[i], &s->subscribers[i + 1],
            (size_t)(s->count - i - 1) * sizeof(s->subscribers[0]));
    s->count--;
}

bool ob_scheduler_is_subscribed(const ob_scheduler_t *s, ob_tick_fn_t fn, void *ctx) {
    return find(s, fn, ctx) >= 0;
}

void ob_scheduler_tick(ob_scheduler_t *s, uint32_t now_ms) {
    if (s->started) {
        /* Unsigned difference: correct across the 2^32 ms wrap. */
        s->last_dt_ms = now_ms - s->now_ms;
        if (s->last_dt_ms > 1u) {
            s->late_ticks++;
        }
    } else {
        s->started = true;
        s->last_dt_ms = 0u;
    }
    s->now_ms = now_ms;
    s->tick_count++;

    int n = s->count;
    ob_subscriber_t round[OB_SCHEDULER_MAX_SUBSCRIBERS];
    memcpy(round, s->subscribers, (size_t)n * sizeof(round[0]));
    for (int i = 0; i < n; i++) {
        /* Fast path: the registry is unchanged at this slot (the usual case). */
        bool present = (i < s->count && s->subscribers[i].fn == round[i].fn &&
                        s->subscribers[i].ctx == round[i].ctx) ||
                       find(s, round[i].fn, round[i].ctx) >= 0;
        if (present) {
            round[i].fn(round[i].ctx, now_ms);
        }
    }
}
