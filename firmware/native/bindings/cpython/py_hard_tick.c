/*
 * motor_process.hard_tick_count() and hard_tick_selftest() on the host (MicroPython: mp_hard_tick.c).
 *
 * The hard tick (hard_tick.h) runs on a POSIX thread here, started by the
 * first self-test; it never touches Python. On the hub it is ESP-IDF's
 * esp_timer, started with the firmware.
 */
#include "bindings.h"
#include "hard_tick.h"
#include "hard_timer.h"

static ob_hard_tick_t hard_tick;

static void fire(void *ctx) {
    ob_hard_tick_fire(ctx);
}

PyObject *ob_py_hard_tick_count(PyObject *self, PyObject *unused) {
    (void)self;
    (void)unused;
    return PyLong_FromUnsignedLong(hard_tick.count);
}

PyObject *ob_py_hard_tick_selftest(PyObject *self, PyObject *args, PyObject *kwargs) {
    (void)self;
    static char *kwlist[] = {"duration_ms", NULL};
    int duration_ms = 100;
    if (!PyArg_ParseTupleAndKeywords(args, kwargs, "|i:hard_tick_selftest", kwlist, &duration_ms)) {
        return NULL;
    }
    if (duration_ms < 10 || duration_ms > 10000) {
        PyErr_Format(PyExc_ValueError, "hard_tick_selftest(duration_ms=%d): give 10..10000 ms", duration_ms);
        return NULL;
    }
    if (!hard_tick.running) {
        if (!ob_hard_timer_start(fire, &hard_tick, OB_HARD_TICK_PERIOD_US)) {
            PyErr_SetString(PyExc_OSError, "hard_tick_selftest: the 1 kHz hard timer could not be started");
            return NULL;
        }
        hard_tick.running = true;
        Py_BEGIN_ALLOW_THREADS
        ob_hard_timer_sleep_ms(OB_HARD_TICK_SETTLE_MS); /* a timer just started counts from its first period */
        Py_END_ALLOW_THREADS
    }
    uint32_t count0 = hard_tick.count, start_us = ob_hard_timer_now_us(), ticks, elapsed_us;
    Py_BEGIN_ALLOW_THREADS
    ob_hard_timer_sleep_ms((uint32_t)duration_ms);
    Py_END_ALLOW_THREADS
    elapsed_us = ob_hard_timer_now_us() - start_us;
    ticks = hard_tick.count - count0;
    /* A host's timer thread may wait for a core and then deliver what it owes: give it that long. */
    for (uint32_t waited = 0; !ob_hard_tick_rate_ok(ticks, elapsed_us) && waited < OB_HARD_TICK_GRACE_MS; waited++) {
        Py_BEGIN_ALLOW_THREADS
        ob_hard_timer_sleep_ms(1);
        Py_END_ALLOW_THREADS
        ticks = hard_tick.count - count0;
    }
    uint32_t expected = ob_hard_tick_expected(elapsed_us);
    if (!ob_hard_tick_rate_ok(ticks, elapsed_us)) {
        PyErr_Format(PyExc_RuntimeError,
                     "hard_tick_selftest: %lu hard ticks in %lu us, expected about %lu: the 1 kHz hard tick is not "
                     "keeping its rate",
                     (unsigned long)ticks, (unsigned long)elapsed_us, (unsigned long)expected);
        return NULL;
    }
    return Py_BuildValue("(kk)", (unsigned long)ticks, (unsigned long)expected);
}
