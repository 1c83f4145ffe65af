/*
 * The hard tick's timer on host builds (hard_timer.h): a detached POSIX thread
 * that wakes on absolute 1 ms deadlines (so sleeping late never drifts the
 * rate) and calls the callback. It touches no interpreter state. The motor
 * lock is a recursive pthread mutex.
 */
#define _POSIX_C_SOURCE 200112L
#define _XOPEN_SOURCE 500 /* PTHREAD_MUTEX_RECURSIVE */

#include <pthread.h>
#include <time.h>

#include "hard_timer.h"

static ob_hard_timer_fn_t timer_fn;
static void *timer_ctx;
static long timer_period_ns;
static int started;
static pthread_mutex_t motor_lock;
static pthread_once_t motor_lock_once = PTHREAD_ONCE_INIT;

static void motor_lock_init(void) {
    pthread_mutexattr_t attr;
    pthread_mutexattr_init(&attr);
    pthread_mutexattr_settype(&attr, PTHREAD_MUTEX_RECURSIVE);
    pthread_mutex_init(&motor_lock, &attr);
    pthread_mutexattr_destroy(&attr);
}

void ob_hard_timer_lock(void) {
    pthread_once(&motor_lock_once, motor_lock_init);
    pthread_mutex_lock(&motor_lock);
}

bool ob_hard_timer_try_lock(void) {
    pthread_once(&motor_lock_once, motor_lock_init);
    return pthread_mutex_trylock(&motor_lock) == 0;
}

void ob_hard_timer_unlock(void) {
    pthread_mutex_unlock(&motor_lock);
}

static void *run(void *unused) {
    (void)unused;
    struct timespec next;
    clock_gettime(CLOCK_MONOTONIC, &next);
    for (;;) {
        next.tv_nsec += timer_period_ns;
        while (next.tv_nsec >= 1000000000L) {
            next.tv_nsec -= 1000000000L;
            next.tv_sec++;
        }
        while (clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &next, NULL) != 0) {
        }
        timer_fn(timer_ctx);
    }
    return NULL;
}

bool ob_hard_timer_start(ob_hard_timer_fn_t fn, void *ctx, uint32_t period_us) {
    if (started) {
        return true;
    }
    timer_fn = fn;
    timer_ctx = ctx;
    timer_period_ns = (long)period_us * 1000L;
    pthread_attr_t attr;
    pthread_t thread;
    if (pthread_attr_init(&attr) != 0) {
        return false;
    }
    pthread_attr_setdetachstate(&attr, PTHREAD_CREATE_DETACHED);
    int rc = pthread_create(&thread, &attr, run, NULL);
    pthread_attr_destroy(&attr);
    started = rc == 0;
    return started != 0;
}

uint32_t ob_hard_timer_now_us(void) {
    struct timespec now;
    clock_gettime(CLOCK_MONOTONIC, &now);
    return (uint32_t)((uint64_t)now.tv_sec * 1000000u + (uint64_t)now.tv_nsec / 1000u);
}

void ob_hard_timer_sleep_ms(uint32_t ms) {
    struct timespec delay = {(time_t)(ms / 1000u), (long)(ms % 1000u) * 1000000L};
    while (nanosleep(&delay, &delay) != 0) {
    }
}
