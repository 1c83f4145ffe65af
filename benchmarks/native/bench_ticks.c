/*
 * Nanoseconds per control tick of the drivebase and servo cores, in pure C.
 *
 * Each controller drives a toy first-order wheel (speed follows duty with a
 * 33 ms time constant, as the ST-3032 model does), so the trajectories,
 * observers, PID and landing logic run their real paths; moves are re-armed
 * whenever one finishes, so every tick is a tick of an active controller.
 *
 * Output, one line per case: "<case> <best ns/tick> <median ns/tick>".
 */
#define _POSIX_C_SOURCE 199309L

#include <stdio.h>
#include <stdlib.h>
#include <time.h>

#include "drivebase.h"
#include "servo.h"

#define TICKS 400000
#define ROUNDS 7

typedef struct {
    float angle_deg;
    float speed_dps;
    float duty_pct;
} toy_wheel_t;

static bool toy_read(void *ctx, float *angle_deg) {
    toy_wheel_t *w = ctx;
    /* Advance 1 ms under the last duty, then report the angle in whole 4096-count steps. */
    w->speed_dps += (w->duty_pct * 8.88f - w->speed_dps) * (0.001f / 0.033f);
    w->angle_deg += w->speed_dps * 0.001f;
    *angle_deg = (float)(long)(w->angle_deg * (4096.0f / 360.0f)) * (360.0f / 4096.0f);
    return true;
}

static void toy_write(void *ctx, float duty_pct) {
    ((toy_wheel_t *)ctx)->duty_pct = duty_pct;
}

static void toy_coast(void *ctx) {
    ((toy_wheel_t *)ctx)->duty_pct = 0.0f;
}

static toy_wheel_t wheels[4];
static ob_drivebase_t db;
static ob_servo_t servos[2];
static float direction = 1.0f;

static void setup(void) {
    ob_motor_io_t io[4];
    for (int i = 0; i < 4; i++) {
        wheels[i] = (toy_wheel_t){0.0f, 0.0f, 0.0f};
        io[i] = (ob_motor_io_t){toy_read, toy_write, toy_coast, &wheels[i]};
    }
    ob_drivebase_init(&db, &io[0], &io[1], 56.0f, 114.0f);
    ob_servo_config_t cfg;
    ob_servo_config_default(&cfg);
    ob_servo_init(&servos[0], &io[2], &cfg);
    ob_servo_init(&servos[1], &io[3], &cfg);
}

static void keep_busy(uint32_t now_ms) {
    if (ob_drivebase_done(&db)) {
        direction = -direction;
        ob_drivebase_straight(&db, 300.0f * direction, OB_THEN_HOLD);
    }
    for (int i = 0; i < 2; i++) {
        if (ob_servo_is_done(&servos[i])) {
            ob_servo_run_angle(&servos[i], 500.0f, 720.0f * direction, OB_THEN_HOLD);
        }
    }
    (void)now_ms;
}

typedef enum { CASE_DRIVEBASE, CASE_SERVO, CASE_PERIOD } bench_case_t;

static double run_round(bench_case_t which, uint32_t *clock_ms) {
    struct timespec t0, t1;
    clock_gettime(CLOCK_MONOTONIC, &t0);
    for (int i = 0; i < TICKS; i++) {
        uint32_t now = (*clock_ms)++;
        if ((now & 63u) == 0u) {
            keep_busy(now);
        }
        switch (which) {
        case CASE_DRIVEBASE:
            ob_drivebase_tick(&db, now);
            break;
        case CASE_SERVO:
            ob_servo_tick(&servos[0], now);
            break;
        case CASE_PERIOD:
            ob_drivebase_tick(&db, now);
            ob_servo_tick(&servos[0], now);
            ob_servo_tick(&servos[1], now);
            break;
        }
    }
    clock_gettime(CLOCK_MONOTONIC, &t1);
    double ns = (double)(t1.tv_sec - t0.tv_sec) * 1e9 + (double)(t1.tv_nsec - t0.tv_nsec);
    return ns / TICKS;
}

static int by_value(const void *a, const void *b) {
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

int main(void) {
    static const char *const names[] = {"drivebase_tick", "servo_tick", "control_period"};
    setup();
    uint32_t clock_ms = 0;
    for (int which = 0; which < 3; which++) {
        double ns[ROUNDS];
        run_round((bench_case_t)which, &clock_ms); /* warm caches and branch predictors */
        for (int r = 0; r < ROUNDS; r++) {
            ns[r] = run_round((bench_case_t)which, &clock_ms);
        }
        qsort(ns, ROUNDS, sizeof(ns[0]), by_value);
        printf("%s %.1f %.1f\n", names[which], ns[0], ns[ROUNDS / 2]);
    }
    return 0;
}
