/*
 * Gyro-Z heading integrator with stationarity-gated bias learning: see imu_yaw.h.
 */
#include "imu_yaw.h"

#include <math.h>
#include <stddef.h>

#define US_PER_S 1e6f

void ob_imu_yaw_default_config(ob_imu_yaw_config_t *cfg) {
    cfg->scale = -1.0f;
    cfg->still_band_dps = 1.5f;
    cfg->settle_us = 500000u;
    cfg->track_tau_s = 10.0f;
    cfg->max_bias_dps = 5.0f;
}

static void window_restart(ob_imu_yaw_t *yaw, float gyro_z_dps) {
    yaw->window_ref_dps = gyro_z_dps;
    yaw->window_sum_dps_s = 0.0f;
    yaw->window_drift_deg = 0.0f;
    yaw->window_us = 0;
}

void ob_imu_yaw_init(ob_imu_yaw_t *yaw, const ob_imu_yaw_config_t *cfg) {
    if (cfg != NULL) {
        yaw->cfg = *cfg;
    } else {
        ob_imu_yaw_default_config(&yaw->cfg);
    }
    yaw->heading_deg = 0.0f;
    yaw->heading_carry_deg = 0.0f;
    yaw->rate_dps = 0.0f;
    yaw->bias_dps = 0.0f;
    yaw->calibrated = false;
    yaw->have_sample = false;
    yaw->last_us = 0;
    yaw->last_gyro_dps = 0.0f;
    window_restart(yaw, 0.0f);
}

/* Kahan step: the carry keeps the part of each increment the running sum could not hold. */
static void heading_add(ob_imu_yaw_t *yaw, float delta_deg) {
    float y = delta_deg - yaw->heading_carry_deg;
    float t = yaw->heading_deg + y;
    yaw->heading_carry_deg = (t - yaw->heading_deg) - y;
    yaw->heading_deg = t;
}

/*
 * A still window just ended with mean raw rate mean_dps. The first one locks
 * the bias and takes back the heading it drifted meanwhile (the robot did not
 * turn, so all of it was bias); later ones only low-pass the bias.
 */
static void window_complete(ob_imu_yaw_t *yaw, float mean_dps, float window_s) {
    if (fabsf(mean_dps) > yaw->cfg.max_bias_dps) {
        return;
    }
    if (!yaw->calibrated) {
        heading_add(yaw, -yaw->window_drift_deg);
        yaw->bias_dps = mean_dps;
        yaw->calibrated = true;
        return;
    }
    float gain = yaw->cfg.track_tau_s > 0.0f ? window_s / yaw->cfg.track_tau_s : 1.0f;
    if (gain > 1.0f) {
        gain = 1.0f;
    }
    yaw->bias_dps += gain * (mean_dps - yaw->bias_dps);
}

static void stillness_update(ob_imu_yaw_t *yaw, float prev_dps, float gyro_z_dps, uint32_t dt_us) {
    float ref_dps = yaw->calibrated ? yaw->bias_dps : yaw->window_ref_dps;
    if (fabsf(gyro_z_dps - ref_dps) > yaw->cfg.still_band_dps) {
        window_restart(yaw, gyro_z_dps);
        return;
    }
    yaw->window_sum_dps_s += 0.5f * (prev_dps + gyro_z_dps) * ((float)dt_us / US_PER_S);
    yaw->window_us += dt_us;
    if (yaw->window_us >= yaw->cfg.settle_us && yaw->window_us > 0) {
        float window_s = (float)yaw->window_us / US_PER_S;
        window_complete(yaw, yaw->window_sum_dps_s / window_s, window_s);
        window_restart(yaw, gyro_z_dps);
    }
}

void ob_imu_yaw_update(ob_imu_yaw_t *yaw, float gyro_z_dps, uint32_t now_us) {
    /* A garbled read is a missed sample: one NaN would otherwise poison the heading for good. */
    if (!isfinite(gyro_z_dps)) {
        return;
    }
    if (!yaw->have_sample) {
        yaw->have_sample = true;
        yaw->last_us = now_us;
        yaw->last_gyro_dps = gyro_z_dps;
        yaw->rate_dps = yaw->cfg.scale * (gyro_z_dps - yaw->bias_dps);
        window_restart(yaw, gyro_z_dps);
        return;
    }
    /* Unsigned difference: correct across the clock's wrap. */
    uint32_t dt_us = now_us - yaw->last_us;
    float prev_dps = yaw->last_gyro_dps;
    yaw->last_us = now_us;
    yaw->last_gyro_dps = gyro_z_dps;
    yaw->rate_dps = yaw->cfg.scale * (gyro_z_dps - yaw->bias_dps);
    if (dt_us > OB_IMU_YAW_MAX_GAP_US) {
        window_restart(yaw, gyro_z_dps);
        return;
    }
    /* Trapezoid between the two samples, both corrected with the current bias. */
    float prev_rate_dps = yaw->cfg.scale * (prev_dps - yaw->bias_dps);
    float step_deg = 0.5f * (prev_rate_dps + yaw->rate_dps) * ((float)dt_us / US_PER_S);
    heading_add(yaw, step_deg);
    yaw->window_drift_deg += step_deg;
    stillness_update(yaw, prev_dps, gyro_z_dps, dt_us);
}

float ob_imu_yaw_heading_deg(const ob_imu_yaw_t *yaw) {
    return yaw->heading_deg;
}

float ob_imu_yaw_rate_dps(const ob_imu_yaw_t *yaw) {
    return yaw->rate_dps;
}

void ob_imu_yaw_reset_heading(ob_imu_yaw_t *yaw, float heading_deg) {
    yaw->heading_deg = heading_deg;
    yaw->heading_carry_deg = 0.0f;
    /* Drift from before the reset is gone with the old frame; a lock must not take it back again. */
    yaw->window_drift_deg = 0.0f;
}

float ob_imu_yaw_bias_dps(const ob_imu_yaw_t *yaw) {
    return yaw->bias_dps;
}

bool ob_imu_yaw_calibrated(const ob_imu_yaw_t *yaw) {
    return yaw->calibrated;
}

bool ob_imu_yaw_seed_bias(ob_imu_yaw_t *yaw, float bias_dps) {
    if (!isfinite(bias_dps) || fabsf(bias_dps) > yaw->cfg.max_bias_dps) {
        return false;
    }
    yaw->bias_dps = bias_dps;
    yaw->calibrated = true;
    if (yaw->have_sample) {
        yaw->rate_dps = yaw->cfg.scale * (yaw->last_gyro_dps - bias_dps);
    }
    /* Judge stillness against the new bias from a fresh window. */
    window_restart(yaw, yaw->last_gyro_dps);
    return true;
}
