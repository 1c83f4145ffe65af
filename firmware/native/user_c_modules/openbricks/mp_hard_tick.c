/*
 * The hard tick in the MicroPython binding, and motor_process.hard_tick_count()
 * and hard_tick_selftest() (host: py_hard_tick.c).
 *
 * The hard tick (hard_tick.h) runs on ESP-IDF's esp_timer on the hub
 * (mp_hard_timer_esp32.c) and on a POSIX thread in the unix port
 * (platform/hard_timer_posix.c); either way it never touches the VM. It
 * starts when motor_process gets its first subscriber (or with a self-test)
 * and each period runs motor_process's hard work (mp_scheduler.c): the
 * control tick itself when every subscriber is native.
 */
#include "hard_tick.h"
#include "hard_timer.h"
#include "mp_bindings.h"
#include "py/mphal.h"

static ob_hard_tick_t hard_tick;

/* The objects whose sensors the hard tick polls, kept reachable for the GC while it does. */
#define POLLED_MAX 12
MP_REGISTER_ROOT_POINTER(mp_obj_t ob_hard_tick_polled[12]);
MP_STATIC_ASSERT(POLLED_MAX == OB_HARD_TICK_MAX_POLLS);
static void *polled_ctx[POLLED_MAX];

static void fire(void *ctx) {
    ob_hard_tick_fire(ctx);
}

void ob_mp_hard_tick_start(void) {
    if (hard_tick.running) {
        return;
    }
    hard_tick.work = ob_mp_motor_process_hard_work;
    hard_tick.work_ctx = NULL;
    if (!ob_hard_timer_start(fire, &hard_tick, OB_HARD_TICK_PERIOD_US)) {
        mp_raise_msg(&mp_type_OSError, MP_ERROR_TEXT("motor_process: the 1 kHz hard timer could not be started"));
    }
    hard_tick.running = true;
}

void ob_mp_hard_tick_poll(mp_obj_t owner, ob_hard_tick_poll_fn_t fn, void *ctx) {
    int slot = -1;
    for (int i = 0; i < POLLED_MAX; i++) {
        if (MP_STATE_VM(ob_hard_tick_polled)[i] == MP_OBJ_NULL) {
            slot = i;
            break;
        }
    }
    ob_hard_timer_lock();
    bool added = slot >= 0 && ob_hard_tick_add_poll(&hard_tick, fn, ctx);
    ob_hard_timer_unlock();
    if (!added) {
        mp_raise_msg_varg(&mp_type_OSError,
                          MP_ERROR_TEXT("the hard tick reads %d sensors already (PCNT encoders and IMUs); "
                                        "close() one you no longer use"),
                          POLLED_MAX);
    }
    MP_STATE_VM(ob_hard_tick_polled)[slot] = owner;
    polled_ctx[slot] = ctx;
    ob_mp_hard_tick_start();
}

void ob_mp_hard_tick_unpoll(void *ctx) {
    ob_hard_timer_lock();
    ob_hard_tick_remove_poll(&hard_tick, ctx);
    ob_hard_timer_unlock();
    for (int i = 0; i < POLLED_MAX; i++) {
        if (polled_ctx[i] == ctx) {
            polled_ctx[i] = NULL;
            MP_STATE_VM(ob_hard_tick_polled)[i] = MP_OBJ_NULL;
        }
    }
}

static mp_obj_t hard_tick_count(mp_obj_t self_in) {
    (void)self_in;
    return mp_obj_new_int_from_uint(hard_tick.count);
}
MP_DEFINE_CONST_FUN_OBJ_1(ob_mp_hard_tick_count_obj, hard_tick_count);

static mp_obj_t hard_tick_selftest(size_t n_args, const mp_obj_t *pos_args, mp_map_t *kw_args) {
    enum { ARG_duration_ms };
    static const mp_arg_t allowed[] = {
        {MP_QSTR_duration_ms, MP_ARG_INT, {.u_int = 100}},
    };
    mp_arg_val_t vals[MP_ARRAY_SIZE(allowed)];
    mp_arg_parse_all(n_args - 1, pos_args + 1, kw_args, MP_ARRAY_SIZE(allowed), allowed, vals);
    mp_int_t duration_ms = vals[ARG_duration_ms].u_int;
    if (duration_ms < 10 || duration_ms > 10000) {
        mp_raise_msg_varg(&mp_type_ValueError, MP_ERROR_TEXT("hard_tick_selftest(duration_ms=%d): give 10..10000 ms"),
                          (int)duration_ms);
    }
    if (!hard_tick.running) {
        ob_mp_hard_tick_start();
        mp_hal_delay_ms(OB_HARD_TICK_SETTLE_MS); /* a timer just started counts from its first period */
    }
    uint32_t count0 = hard_tick.count;
    uint32_t dispatched0 = hard_tick.dispatched;
    uint32_t contended0 = hard_tick.contended;
    bool dispatching = ob_mp_motor_process_hard_ticked();
    uint32_t start_us = ob_hard_timer_now_us();
    mp_hal_delay_ms((mp_uint_t)duration_ms);
    uint32_t elapsed_us = ob_hard_timer_now_us() - start_us;
    uint32_t ticks = hard_tick.count - count0;
    /* A host's timer thread may wait for a core and then deliver what it owes: give it that long. */
    for (uint32_t waited = 0; !ob_hard_tick_rate_ok(ticks, elapsed_us) && waited < OB_HARD_TICK_GRACE_MS; waited++) {
        mp_hal_delay_ms(1);
        ticks = hard_tick.count - count0;
    }
    uint32_t expected = ob_hard_tick_expected(elapsed_us);
    if (!ob_hard_tick_rate_ok(ticks, elapsed_us)) {
        mp_raise_msg_varg(&mp_type_RuntimeError,
                          MP_ERROR_TEXT("hard_tick_selftest: %u hard ticks in %u us, expected about %u: the 1 kHz hard "
                                        "tick is not keeping its rate"),
                          (unsigned)ticks, (unsigned)elapsed_us, (unsigned)expected);
    }
    /* While it runs the controllers, each period must also have run motor_process (not been skipped). */
    uint32_t dispatched = hard_tick.dispatched - dispatched0;
    if (dispatching && ob_mp_motor_process_hard_ticked() && !ob_hard_tick_rate_ok(dispatched, elapsed_us)) {
        mp_raise_msg_varg(&mp_type_RuntimeError,
                          MP_ERROR_TEXT("hard_tick_selftest: the hard tick ran motor_process %u times in %u us "
                                        "(expected about %u; %u periods found the interpreter holding the motor lock)"),
                          (unsigned)dispatched, (unsigned)elapsed_us, (unsigned)expected,
                          (unsigned)(hard_tick.contended - contended0));
    }
    mp_obj_t items[2] = {mp_obj_new_int_from_uint(ticks), mp_obj_new_int_from_uint(expected)};
    return mp_obj_new_tuple(2, items);
}
MP_DEFINE_CONST_FUN_OBJ_KW(ob_mp_hard_tick_selftest_obj, 1, hard_tick_selftest);
