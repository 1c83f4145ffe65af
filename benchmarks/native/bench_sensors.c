/*
 * What the hard tick's sensor reads cost each millisecond, in the cores alone:
 * a PCNT encoder poll (read the counter, unwrap, accumulate) and an ICM-45686
 * sample (one 13-byte burst from an in-memory chip, parse, scale, integrate
 * the heading). Prints, one per line: the CPU time of each (best and median
 * of 7 runs, ns per read).
 */
#define _POSIX_C_SOURCE 199309L /* clock_gettime */

#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "encoder.h"
#include "icm45686.h"

#define READS 1000000
#define RUNS 7

/* A shaft at ~340 counts per read (an MG370 flat out) behind a PCNT unit at +-32767. */
static bool counter_read(void *ctx, int32_t *raw) {
    int32_t *value = ctx;
    *value = (*value + 340) % OB_PCNT_LIMIT;
    *raw = *value;
    return true;
}

/* A chip turning at about 90 deg/s: setup registers answer, the data block carries gyro Z. */
static bool chip_transfer(void *ctx, const uint8_t *tx, uint8_t *rx, size_t n) {
    uint32_t *bursts = ctx;
    memset(rx, 0, n);
    if (tx[0] == (OB_ICM45686_REG_WHO_AM_I | OB_ICM45686_READ) && n > 1) {
        rx[1] = OB_ICM45686_WHO_AM_I;
    } else if (tx[0] == (OB_ICM45686_REG_ACCEL_DATA_X1 | OB_ICM45686_READ) && n == 13) {
        int16_t gz = (int16_t)(-2949 + (int)(*bursts % 7u));
        rx[5] = 0x20; /* accel z: +1 g at +-4 g */
        rx[11] = (uint8_t)((uint16_t)gz & 0xFFu);
        rx[12] = (uint8_t)((uint16_t)gz >> 8);
        (*bursts)++;
    }
    return true;
}

static void no_delay(void *ctx, uint32_t ms) {
    (void)ctx;
    (void)ms;
}

static double now_ns(void) {
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec * 1e9 + (double)ts.tv_nsec;
}

static int compare(const void *a, const void *b) {
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

static void report(const char *name, double *per_read) {
    qsort(per_read, RUNS, sizeof(per_read[0]), compare);
    printf("%s %.1f %.1f\n", name, per_read[0], per_read[RUNS / 2]);
}

int main(void) {
    static int32_t counter;
    ob_pcnt_t pcnt = {counter_read, &counter};
    ob_encoder_config_t cfg;
    ob_encoder_default_config(&cfg, 68028);
    ob_encoder_t enc;
    ob_encoder_init(&enc, &cfg, &pcnt);
    double per_read[RUNS];
    for (int run = 0; run < RUNS; run++) {
        double start = now_ns();
        for (uint32_t i = 0; i < READS; i++) {
            ob_encoder_poll(&enc);
        }
        per_read[run] = (now_ns() - start) / READS;
    }
    if (ob_encoder_count(&enc) != (int64_t)340 * (RUNS * READS - 1)) {
        fprintf(stderr, "encoder miscounted: %lld\n", (long long)ob_encoder_count(&enc));
        return 1;
    }
    report("encoder_poll", per_read);

    static uint32_t bursts;
    ob_spi_t spi = {chip_transfer, no_delay, &bursts};
    static ob_icm45686_t imu;
    ob_icm45686_init(&imu, &spi, NULL);
    if (ob_icm45686_configure(&imu) != OB_ICM45686_OK) {
        fprintf(stderr, "ICM-45686 setup failed\n");
        return 1;
    }
    uint32_t now_us = 0;
    for (int run = 0; run < RUNS; run++) {
        double start = now_ns();
        for (uint32_t i = 0; i < READS; i++) {
            now_us += 1000u;
            ob_icm45686_sample(&imu, now_us);
        }
        per_read[run] = (now_ns() - start) / READS;
    }
    if (imu.read_errors != 0u) {
        fprintf(stderr, "ICM-45686 samples failed\n");
        return 1;
    }
    report("icm45686_sample", per_read);
    return 0;
}
