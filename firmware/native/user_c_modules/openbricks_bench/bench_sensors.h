/*
 * Emulated sensors for the unix port's hard-tick tests, in portable C: a
 * shaft seen through a PCNT unit, and an ICM-45686 on the body of a robot
 * whose wheels are emulated ST-3032s (bench_servos.h).
 *
 * PCNT: the unit counts every edge and returns to 0 at +-OB_PCNT_LIMIT, so
 * its reading repeats every 32767 counts; only a reader that samples often
 * enough (the hard tick) can follow the shaft.
 *
 * ICM-45686: the register file the driver touches (WHO_AM_I 0xE9, soft
 * reset, configs, power) and the 12-byte data block (accel 0, 0, +1 g; gyro
 * x, y 0 and z the body's rate, counter-clockwise-positive for a face-up
 * chip, plus a bias), at the full scales the configs select. The body turns
 * as its wheels say (no-slip kinematics) times true_scale: a robot whose
 * tyres scrub turns less than its encoders think, which only a gyro sees.
 */
#ifndef OB_BENCH_SENSORS_H
#define OB_BENCH_SENSORS_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "bench_servos.h"

typedef struct {
    double counts;   /* true position */
    double rate_cps; /* counts per second */
    uint32_t last_us;
    int32_t raw;     /* what the PCNT unit reads */
    uint32_t reads;
} ob_bench_shaft_t;

void ob_bench_shaft_init(ob_bench_shaft_t *shaft, uint32_t now_us);

/* Turn at rate_cps from now on. */
void ob_bench_shaft_set_rate(ob_bench_shaft_t *shaft, double rate_cps, uint32_t now_us);

/* Advance to now_us and return the PCNT unit's reading. */
int32_t ob_bench_shaft_read(ob_bench_shaft_t *shaft, uint32_t now_us);

/* True position in counts at now_us. */
int64_t ob_bench_shaft_count(ob_bench_shaft_t *shaft, uint32_t now_us);

typedef struct {
    uint8_t regs[128];
    ob_bench_bus_t *bus;
    uint8_t left_id, right_id;
    bool right_inverted;  /* the right wheel's servo is mounted mirror-image */
    double wheel_mm, track_mm;
    double true_scale;    /* body rotation per wheel-derived rotation */
    double bias_dps;
    uint32_t bursts;
    uint32_t last_burst_us;
    uint32_t max_gap_us;  /* longest time between two bursts: how long the reader stalled */
    double last_burst_heading_deg;
    /*
     * True rotation during gaps between bursts longer than the heading integrator bridges
     * (OB_IMU_YAW_MAX_GAP_US): what no gyro reader could have seen. A host's timer thread can
     * stall that long under load; the hub's esp_timer does not.
     */
    double unseen_deg;
} ob_bench_imu_t;

void ob_bench_imu_init(ob_bench_imu_t *imu, ob_bench_bus_t *bus, uint8_t left_id, uint8_t right_id,
                       bool right_inverted, double wheel_mm, double track_mm, double true_scale, double bias_dps);

/* One chip-select window at now_us. False when a wheel servo is missing from the bus. */
bool ob_bench_imu_transfer(ob_bench_imu_t *imu, const uint8_t *tx, uint8_t *rx, size_t n, uint32_t now_us);

/* The body's true heading at now_us, CW-positive degrees, from the wheels' angles. */
double ob_bench_imu_true_heading_deg(ob_bench_imu_t *imu, uint32_t now_us);

#endif /* OB_BENCH_SENSORS_H */
