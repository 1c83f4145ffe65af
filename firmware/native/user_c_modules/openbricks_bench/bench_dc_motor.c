/*
 * Emulated DC gear motor with encoder (see bench_dc_motor.h).
 */
#include "bench_dc_motor.h"

#include <string.h>

#define DRIVE_TAU_S 0.05     /* a JGB37-520's speed response to a duty step, and to a brake */
#define FREEWHEEL_TAU_S 0.15 /* coasting, only the gearbox slows it */
#define MAX_STEP_S 0.001     /* integration step */

void ob_bench_dc_motor_init(ob_bench_dc_motor_t *motor, double no_load_dps, double counts_per_rev, uint32_t duty_max,
                            uint32_t now_us) {
    memset(motor, 0, sizeof(*motor));
    ob_bench_shaft_init(&motor->encoder, now_us);
    motor->counts_per_rev = counts_per_rev;
    motor->no_load_cps = no_load_dps * counts_per_rev / 360.0;
    motor->duty_max = duty_max;
    motor->last_us = now_us;
}

/* The speed the levels drive the shaft towards, counts/s, and how fast it gets there. */
static double target_cps(const ob_bench_dc_motor_t *motor, double *tau_s) {
    double share = motor->duty_max == 0u ? 0.0 : (double)motor->duty / (double)motor->duty_max;
    *tau_s = DRIVE_TAU_S;
    if (share > 0.0 && motor->in1 != motor->in2) {
        return (motor->in1 ? share : -share) * motor->no_load_cps;
    }
    if (share > 0.0 && motor->in1 && motor->in2) {
        return 0.0; /* brake: the shorted winding */
    }
    *tau_s = FREEWHEEL_TAU_S;
    return 0.0;
}

static void advance(ob_bench_dc_motor_t *motor, uint32_t now_us) {
    uint32_t left_us = now_us - motor->last_us;
    if (left_us > 1000000u) {
        left_us = 1000000u; /* a paused test: the shaft has long settled */
        motor->last_us = now_us - left_us;
    }
    double tau_s;
    double target = target_cps(motor, &tau_s);
    while (left_us > 0u) {
        uint32_t step_us = left_us < (uint32_t)(MAX_STEP_S * 1e6) ? left_us : (uint32_t)(MAX_STEP_S * 1e6);
        double dt = (double)step_us * 1e-6;
        motor->speed_cps += (target - motor->speed_cps) * (dt / (tau_s + dt));
        motor->last_us += step_us;
        left_us -= step_us;
        /* The encoder runs at the old speed up to the step's start, then at the new one. */
        ob_bench_shaft_set_rate(&motor->encoder, motor->speed_cps, motor->last_us - step_us);
    }
}

void ob_bench_dc_motor_write(ob_bench_dc_motor_t *motor, bool in1, bool in2, uint32_t duty, uint32_t now_us) {
    advance(motor, now_us);
    motor->in1 = in1;
    motor->in2 = in2;
    motor->duty = duty > motor->duty_max ? motor->duty_max : duty;
    motor->writes++;
}

int32_t ob_bench_dc_motor_read(ob_bench_dc_motor_t *motor, uint32_t now_us) {
    advance(motor, now_us);
    return ob_bench_shaft_read(&motor->encoder, now_us);
}

double ob_bench_dc_motor_angle_deg(ob_bench_dc_motor_t *motor, uint32_t now_us) {
    advance(motor, now_us);
    return (double)ob_bench_shaft_count(&motor->encoder, now_us) * 360.0 / motor->counts_per_rev;
}
