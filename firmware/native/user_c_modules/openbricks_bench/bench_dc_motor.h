/*
 * An emulated DC gear motor with its quadrature encoder, in portable C, for
 * the unix port's hard-tick tests of the DC drive path: what an H-bridge's
 * pins (hbridge_pins.h) drive, and what a PCNT unit counts.
 *
 * The shaft is a first-order speed response to the bridge: forward (IN1 high,
 * IN2 low) towards the EN duty's share of the no-load speed, reverse the other
 * way, brake (both high) to rest as fast as it speeds up, coast (both low or
 * EN off) to rest slowly on the gearbox's friction. The encoder is the bench
 * PCNT shaft (bench_sensors.h), so its reading returns to 0 every 32767
 * counts as the hub's does and only a reader on the hard tick keeps up.
 */
#ifndef OB_BENCH_DC_MOTOR_H
#define OB_BENCH_DC_MOTOR_H

#include <stdbool.h>
#include <stdint.h>

#include "bench_sensors.h"

typedef struct {
    ob_bench_shaft_t encoder; /* counts at the output shaft, and the PCNT unit's reading of them */
    double no_load_cps;       /* output speed at 100 % duty, counts/s */
    double counts_per_rev;    /* encoder counts per output turn */
    double speed_cps;
    bool in1, in2;            /* the bridge's levels as last written */
    uint32_t duty, duty_max;
    uint32_t last_us;         /* when the speed was last brought up to date */
    uint32_t writes;          /* level changes the bridge wrote */
} ob_bench_dc_motor_t;

/* At rest, coasting; duty_max is the EN scale the emulated pins offer. */
void ob_bench_dc_motor_init(ob_bench_dc_motor_t *motor, double no_load_dps, double counts_per_rev, uint32_t duty_max,
                            uint32_t now_us);

/* The bridge's pins at now_us: the shaft runs on the old levels until then. */
void ob_bench_dc_motor_write(ob_bench_dc_motor_t *motor, bool in1, bool in2, uint32_t duty, uint32_t now_us);

/* The PCNT unit's reading at now_us. */
int32_t ob_bench_dc_motor_read(ob_bench_dc_motor_t *motor, uint32_t now_us);

/* The output shaft's true angle at now_us, degrees since it was made. */
double ob_bench_dc_motor_angle_deg(ob_bench_dc_motor_t *motor, uint32_t now_us);

#endif /* OB_BENCH_DC_MOTOR_H */
