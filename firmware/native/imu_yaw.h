/*
 * Continuous body heading from a gyro's Z rate, with the gyro's zero-rate
 * bias learned whenever the robot stands still.
 *
 * A MEMS gyro reads a small non-zero rate at rest (its bias); integrated,
 * that is a steady heading drift. The bias is estimated only from stretches
 * in which the robot is demonstrably still: every sample of a settle window
 * stays within a narrow band of the reference rate (the current bias once it
 * is known, the window's first sample before). The first such window locks
 * the bias outright (the half-second at boot); later ones nudge it through a
 * slow low-pass, which follows thermal drift without letting a slow crawl of
 * the robot leak in. A bias persisted from an earlier run can be seeded so a
 * program that moves straight after boot is corrected from the first sample.
 * Once a bias is known, stillness is judged against it, so a seed more than
 * still_band_dps off would never be corrected at rest; seeds come from the
 * same sensor, whose bias moves by hundredths of a degree per second.
 *
 * Heading is CW-positive seen from above, like the drivebase, and unwrapped
 * (multi-turn). Time comes from a free-running microsecond clock passed with
 * every sample, so a late or missed sample integrates over the time that
 * really passed.
 */
#ifndef OB_IMU_YAW_H
#define OB_IMU_YAW_H

#include <stdbool.h>
#include <stdint.h>

/*
 * A longer silence between samples is not integrated: the motion during it
 * is unknown, and a straight line between two samples a tenth of a second
 * apart invents rotation. It also restarts the stillness window.
 */
#define OB_IMU_YAW_MAX_GAP_US 100000u

typedef struct {
    /*
     * Heading rate per gyro-Z deg/s. A gyro's Z is counter-clockwise-positive
     * about its own up axis (right-hand rule), so a sensor mounted face up
     * needs -1 and one mounted face down +1.
     */
    float scale;
    float still_band_dps;  /* stillness: every sample within this of the reference rate */
    uint32_t settle_us;    /* ... for this long */
    float track_tau_s;     /* time constant of the bias tracking after the first lock */
    float max_bias_dps;    /* larger "bias" is motion or a broken sensor, never learned or seeded */
} ob_imu_yaw_config_t;

typedef struct {
    ob_imu_yaw_config_t cfg;
    /*
     * Heading as a compensated (Kahan) sum: at 1 kHz a single float running
     * sum loses the low bits of every small increment once the heading is a
     * few turns large, which is a systematic drift during long turns.
     */
    float heading_deg;
    float heading_carry_deg;
    float rate_dps;        /* last bias-corrected heading rate */
    float bias_dps;        /* in the sensor's frame and units, before scale */
    bool calibrated;
    bool have_sample;
    uint32_t last_us;
    float last_gyro_dps;
    /* The stillness window in progress. */
    float window_ref_dps;
    float window_sum_dps_s;   /* time integral of the raw rate over the window */
    float window_drift_deg;   /* heading change integrated during the window */
    uint32_t window_us;
} ob_imu_yaw_t;

/*
 * Defaults for a 1 kHz gyro: face-up mounting, a 1.5 deg/s stillness band,
 * half a second to settle (the manual's boot lock), 10 s tracking, 5 deg/s
 * plausibility bound.
 */
void ob_imu_yaw_default_config(ob_imu_yaw_config_t *cfg);

/* Start at heading 0 with no bias known (0 until the first still window). */
void ob_imu_yaw_init(ob_imu_yaw_t *yaw, const ob_imu_yaw_config_t *cfg);

/*
 * One gyro sample: Z rate in deg/s as the sensor reports it, and the
 * microsecond clock at which it was taken (wrapping uint32 is fine). The
 * first sample only starts the clock; a non-finite rate is dropped like a
 * missed sample.
 */
void ob_imu_yaw_update(ob_imu_yaw_t *yaw, float gyro_z_dps, uint32_t now_us);

/* Continuous heading, CW-positive, degrees. */
float ob_imu_yaw_heading_deg(const ob_imu_yaw_t *yaw);

/* Bias-corrected heading rate of the last sample, CW-positive, deg/s. */
float ob_imu_yaw_rate_dps(const ob_imu_yaw_t *yaw);

/* Make the current pose read heading_deg. The bias and its lock are kept. */
void ob_imu_yaw_reset_heading(ob_imu_yaw_t *yaw, float heading_deg);

/* Current bias estimate in the sensor's deg/s, the value to persist. */
float ob_imu_yaw_bias_dps(const ob_imu_yaw_t *yaw);

/* True once a still window has locked the bias or a bias was seeded. */
bool ob_imu_yaw_calibrated(const ob_imu_yaw_t *yaw);

/*
 * Use a persisted bias from now on and count as calibrated. Returns false and
 * changes nothing when the value is not finite or beyond max_bias_dps (a
 * corrupted store must not steer the robot).
 */
bool ob_imu_yaw_seed_bias(ob_imu_yaw_t *yaw, float bias_dps);

#endif /* OB_IMU_YAW_H */
