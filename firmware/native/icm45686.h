/*
 * The TDK ICM-45686 6-axis IMU on SPI, read inside the hard tick: the
 * gyro heading source of a DriveBase that steers with no Python in the loop.
 *
 * The register map (datasheet DS-000577, bank 0) lives here once. Setup
 * soft-resets the chip, checks WHO_AM_I, selects +-1000 dps / +-4 g at
 * 1.6 kHz and powers both sensors in low-noise mode. Each sample is one
 * 13-byte burst (the register address, then accel x, y, z and gyro x, y, z,
 * little-endian int16): about 13 us at 8 MHz. A sensor that is off, or a
 * sample the chip has not produced yet, reads -32768 ("no data"); such a
 * burst is a missed sample. Gyro Z goes to the heading integrator
 * (imu_yaw.h: bias learned at rest, CW-positive, unwrapped), so the
 * heading, its bias and the stillness detection are the same C whether the
 * hub's hard tick, the simulator or a test feeds it.
 */
#ifndef OB_ICM45686_H
#define OB_ICM45686_H

#include <stdbool.h>
#include <stdint.h>

#include "imu_yaw.h"
#include "spi.h"

/* Register map, bank 0. */
#define OB_ICM45686_REG_ACCEL_DATA_X1 0x00u /* 12 bytes: accel x, y, z, gyro x, y, z */
#define OB_ICM45686_REG_PWR_MGMT0 0x10u
#define OB_ICM45686_REG_ACCEL_CONFIG0 0x1Bu
#define OB_ICM45686_REG_GYRO_CONFIG0 0x1Cu
#define OB_ICM45686_REG_WHO_AM_I 0x72u
#define OB_ICM45686_REG_MISC2 0x7Fu
#define OB_ICM45686_READ 0x80u /* address bit 7: read */

#define OB_ICM45686_MISC2_SOFT_RESET 0x02u
#define OB_ICM45686_WHO_AM_I 0xE9u         /* ICM-45686 */
#define OB_ICM45686_WHO_AM_I_S 0xEEu       /* ICM-45686-S */
#define OB_ICM45686_PWR_LOW_NOISE 0x0Fu    /* gyro and accel in low-noise mode */
#define OB_ICM45686_GYRO_CONFIG 0x25u      /* +-1000 dps (2 << 4), 1.6 kHz (5) */
#define OB_ICM45686_ACCEL_CONFIG 0x35u     /* +-4 g (3 << 4), 1.6 kHz (5) */
#define OB_ICM45686_GYRO_FS_DPS 1000.0f
#define OB_ICM45686_ACCEL_FS_G 4.0f
#define OB_ICM45686_NO_DATA (-32768)
#define OB_ICM45686_BURST_BYTES 12u
#define OB_ICM45686_RESET_MS 2u            /* registers unusable for 1 ms after a soft reset */
#define OB_ICM45686_STARTUP_MS 50u         /* gyro start-up after power on */

typedef enum {
    OB_ICM45686_OK = 0,
    OB_ICM45686_SPI_FAILED, /* the link refused a transfer */
    OB_ICM45686_NO_CHIP,    /* WHO_AM_I is not an ICM-45686's */
} ob_icm45686_error_t;

typedef struct {
    float gyro_dps[3]; /* chip frame, right-handed */
    float accel_g[3];
} ob_icm45686_sample_t;

typedef struct {
    ob_spi_t spi;
    ob_imu_yaw_t yaw;
    ob_icm45686_sample_t last; /* the last good sample */
    uint32_t reads_ok;
    uint32_t read_errors;
    bool configured;
    bool fresh;       /* the last sample was good: the heading is current */
    uint8_t who_am_i; /* as read at setup */
} ob_icm45686_t;

/* Bind the link and the heading integrator's config (NULL: imu_yaw defaults). Nothing is sent yet. */
void ob_icm45686_init(ob_icm45686_t *imu, const ob_spi_t *spi, const ob_imu_yaw_config_t *yaw_cfg);

/* Soft reset, WHO_AM_I check, full scales, power on (waits ~52 ms through spi.delay_ms). */
ob_icm45686_error_t ob_icm45686_configure(ob_icm45686_t *imu);

/* Scale one 12-byte data block; false when either sensor reads "no data". */
bool ob_icm45686_parse(const uint8_t data[OB_ICM45686_BURST_BYTES], ob_icm45686_sample_t *out);

/*
 * One burst read at now_us (the microsecond clock, wrapping): a good sample
 * becomes `last` and feeds gyro Z to the heading; a failed or empty one is
 * counted in read_errors. Returns whether the sample was good.
 */
bool ob_icm45686_sample(ob_icm45686_t *imu, uint32_t now_us);

/*
 * A drivebase heading source (ob_heading_source_t, ctx: ob_icm45686_t *):
 * the integrated heading, false while the last sample failed (the drivebase
 * then bridges with its encoders and halts if it lasts).
 */
bool ob_icm45686_read_heading(void *ctx, float *heading_deg);

/* Text for an ob_icm45686_error_t, for the bindings' messages. */
const char *ob_icm45686_strerror(ob_icm45686_error_t error);

#endif /* OB_ICM45686_H */
