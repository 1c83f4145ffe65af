/*
 * Emulated PCNT shaft and ICM-45686 (see bench_sensors.h).
 */
#include "bench_sensors.h"

#include <math.h>
#include <string.h>

#include "icm45686.h"
#include "imu_yaw.h"
#include "pcnt.h"

#define PI 3.14159265358979323846
#define COUNTS_PER_REV 4096.0

void ob_bench_shaft_init(ob_bench_shaft_t *shaft, uint32_t now_us) {
    memset(shaft, 0, sizeof(*shaft));
    shaft->last_us = now_us;
}

static void advance(ob_bench_shaft_t *shaft, uint32_t now_us) {
    double before = floor(shaft->counts);
    shaft->counts += shaft->rate_cps * (double)(uint32_t)(now_us - shaft->last_us) * 1e-6;
    shaft->last_us = now_us;
    int64_t edges = (int64_t)(floor(shaft->counts) - before);
    /* Between two reads the shaft turns one way: the unit resets to 0 at each limit it reaches. */
    shaft->raw = (int32_t)(((int64_t)shaft->raw + edges) % OB_PCNT_LIMIT);
}

void ob_bench_shaft_set_rate(ob_bench_shaft_t *shaft, double rate_cps, uint32_t now_us) {
    advance(shaft, now_us);
    shaft->rate_cps = rate_cps;
}

int32_t ob_bench_shaft_read(ob_bench_shaft_t *shaft, uint32_t now_us) {
    advance(shaft, now_us);
    shaft->reads++;
    return shaft->raw;
}

int64_t ob_bench_shaft_count(ob_bench_shaft_t *shaft, uint32_t now_us) {
    advance(shaft, now_us);
    return (int64_t)floor(shaft->counts);
}

void ob_bench_imu_init(ob_bench_imu_t *imu, ob_bench_bus_t *bus, uint8_t left_id, uint8_t right_id,
                       bool right_inverted, double wheel_mm, double track_mm, double true_scale, double bias_dps) {
    memset(imu, 0, sizeof(*imu));
    imu->regs[OB_ICM45686_REG_WHO_AM_I] = OB_ICM45686_WHO_AM_I;
    imu->regs[OB_ICM45686_REG_GYRO_CONFIG0] = 0x06;
    imu->regs[OB_ICM45686_REG_ACCEL_CONFIG0] = 0x06;
    imu->bus = bus;
    imu->left_id = left_id;
    imu->right_id = right_id;
    imu->right_inverted = right_inverted;
    imu->wheel_mm = wheel_mm;
    imu->track_mm = track_mm;
    imu->true_scale = true_scale;
    imu->bias_dps = bias_dps;
}

/* Forward wheel travel in mm (angles) or mm/s (speeds) from a servo-frame value in degrees. */
static double forward_mm(const ob_bench_imu_t *imu, double deg, bool inverted) {
    return (inverted ? -deg : deg) * PI * imu->wheel_mm / 360.0;
}

static bool wheels(ob_bench_imu_t *imu, uint32_t now_us, ob_bench_servo_t **left, ob_bench_servo_t **right) {
    *left = ob_bench_bus_find(imu->bus, imu->left_id);
    *right = ob_bench_bus_find(imu->bus, imu->right_id);
    if (*left == NULL || *right == NULL) {
        return false;
    }
    ob_bench_servo_angle_deg(*left, imu->bus->no_load_cps, now_us); /* advance both shafts to now */
    ob_bench_servo_angle_deg(*right, imu->bus->no_load_cps, now_us);
    return true;
}

double ob_bench_imu_true_heading_deg(ob_bench_imu_t *imu, uint32_t now_us) {
    ob_bench_servo_t *left, *right;
    if (!wheels(imu, now_us, &left, &right)) {
        return 0.0;
    }
    double left_mm = forward_mm(imu, left->counts * 360.0 / COUNTS_PER_REV, false);
    double right_mm = forward_mm(imu, right->counts * 360.0 / COUNTS_PER_REV, imu->right_inverted);
    return imu->true_scale * (left_mm - right_mm) / imu->track_mm * 180.0 / PI;
}

static int16_t counts(double value, double full_scale) {
    double c = floor(value * 32768.0 / full_scale + 0.5);
    return (int16_t)(c > 32767.0 ? 32767.0 : (c < -32767.0 ? -32767.0 : c));
}

static void put16(uint8_t *p, int16_t v) {
    p[0] = (uint8_t)((uint16_t)v & 0xFFu);
    p[1] = (uint8_t)((uint16_t)v >> 8);
}

bool ob_bench_imu_transfer(ob_bench_imu_t *imu, const uint8_t *tx, uint8_t *rx, size_t n, uint32_t now_us) {
    static const double gyro_fs[] = {4000.0, 2000.0, 1000.0, 500.0, 250.0, 125.0, 62.5, 31.25, 15.625};
    static const double accel_fs[] = {32.0, 16.0, 8.0, 4.0, 2.0};
    memset(rx, 0, n);
    if (n == 0) {
        return true;
    }
    uint8_t reg = tx[0] & 0x7Fu;
    if ((tx[0] & OB_ICM45686_READ) == 0u) {
        for (size_t i = 1; i < n; i++) {
            uint8_t r = (uint8_t)((reg + i - 1u) & 0x7Fu);
            if (r == OB_ICM45686_REG_MISC2 && (tx[i] & OB_ICM45686_MISC2_SOFT_RESET)) {
                ob_bench_imu_init(imu, imu->bus, imu->left_id, imu->right_id, imu->right_inverted, imu->wheel_mm,
                                  imu->track_mm, imu->true_scale, imu->bias_dps);
            } else if (r != OB_ICM45686_REG_WHO_AM_I) {
                imu->regs[r] = tx[i];
            }
        }
        return true;
    }
    uint8_t block[OB_ICM45686_BURST_BYTES];
    if (reg == OB_ICM45686_REG_ACCEL_DATA_X1) {
        ob_bench_servo_t *left, *right;
        if (!wheels(imu, now_us, &left, &right)) {
            return false;
        }
        uint32_t gap_us = now_us - imu->last_burst_us;
        double heading_deg = ob_bench_imu_true_heading_deg(imu, now_us);
        if (imu->bursts > 0u) {
            if (gap_us > imu->max_gap_us) {
                imu->max_gap_us = gap_us;
            }
            if (gap_us > OB_IMU_YAW_MAX_GAP_US) {
                imu->unseen_deg += heading_deg - imu->last_burst_heading_deg;
            }
        }
        imu->last_burst_us = now_us;
        imu->last_burst_heading_deg = heading_deg;
        imu->bursts++;
        uint8_t pwr = imu->regs[OB_ICM45686_REG_PWR_MGMT0];
        bool accel_on = (pwr & 3u) >= 2u, gyro_on = ((pwr >> 2) & 3u) >= 2u;
        double g_fs = gyro_fs[(imu->regs[OB_ICM45686_REG_GYRO_CONFIG0] >> 4) % 9u];
        double a_fs = accel_fs[((imu->regs[OB_ICM45686_REG_ACCEL_CONFIG0] >> 4) & 7u) % 5u];
        double left_mm_s = forward_mm(imu, left->speed_cps * 360.0 / COUNTS_PER_REV, false);
        double right_mm_s = forward_mm(imu, right->speed_cps * 360.0 / COUNTS_PER_REV, imu->right_inverted);
        double cw_dps = imu->true_scale * (left_mm_s - right_mm_s) / imu->track_mm * 180.0 / PI;
        double gyro[3] = {0.0, 0.0, -cw_dps + imu->bias_dps};
        double accel[3] = {0.0, 0.0, 1.0};
        for (int i = 0; i < 3; i++) {
            put16(&block[2 * i], accel_on ? counts(accel[i], a_fs) : (int16_t)OB_ICM45686_NO_DATA);
            put16(&block[6 + 2 * i], gyro_on ? counts(gyro[i], g_fs) : (int16_t)OB_ICM45686_NO_DATA);
        }
    }
    for (size_t i = 1; i < n; i++) {
        size_t r = reg + i - 1u;
        rx[i] = reg == OB_ICM45686_REG_ACCEL_DATA_X1 && r < sizeof block ? block[r] : imu->regs[r & 0x7Fu];
    }
    return true;
}
