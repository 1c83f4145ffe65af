/*
 * ICM-45686 setup, burst read and scaling: see icm45686.h.
 */
#include "icm45686.h"

#include <stddef.h>

void ob_icm45686_init(ob_icm45686_t *imu, const ob_spi_t *spi, const ob_imu_yaw_config_t *yaw_cfg) {
    imu->spi = *spi;
    ob_imu_yaw_init(&imu->yaw, yaw_cfg);
    for (int i = 0; i < 3; i++) {
        imu->last.gyro_dps[i] = 0.0f;
        imu->last.accel_g[i] = 0.0f;
    }
    imu->reads_ok = 0;
    imu->read_errors = 0;
    imu->configured = false;
    imu->fresh = false;
    imu->who_am_i = 0;
}

static bool write_reg(ob_icm45686_t *imu, uint8_t reg, uint8_t value) {
    uint8_t tx[2] = {reg, value};
    uint8_t rx[2];
    return imu->spi.transfer(imu->spi.ctx, tx, rx, 2);
}

static bool read_reg(ob_icm45686_t *imu, uint8_t reg, uint8_t *value) {
    uint8_t tx[2] = {(uint8_t)(reg | OB_ICM45686_READ), 0};
    uint8_t rx[2] = {0, 0};
    if (!imu->spi.transfer(imu->spi.ctx, tx, rx, 2)) {
        return false;
    }
    *value = rx[1];
    return true;
}

ob_icm45686_error_t ob_icm45686_configure(ob_icm45686_t *imu) {
    imu->configured = false;
    if (!write_reg(imu, OB_ICM45686_REG_MISC2, OB_ICM45686_MISC2_SOFT_RESET)) {
        return OB_ICM45686_SPI_FAILED;
    }
    imu->spi.delay_ms(imu->spi.ctx, OB_ICM45686_RESET_MS);
    if (!read_reg(imu, OB_ICM45686_REG_WHO_AM_I, &imu->who_am_i)) {
        return OB_ICM45686_SPI_FAILED;
    }
    if (imu->who_am_i != OB_ICM45686_WHO_AM_I && imu->who_am_i != OB_ICM45686_WHO_AM_I_S) {
        return OB_ICM45686_NO_CHIP;
    }
    if (!write_reg(imu, OB_ICM45686_REG_GYRO_CONFIG0, OB_ICM45686_GYRO_CONFIG) ||
        !write_reg(imu, OB_ICM45686_REG_ACCEL_CONFIG0, OB_ICM45686_ACCEL_CONFIG) ||
        !write_reg(imu, OB_ICM45686_REG_PWR_MGMT0, OB_ICM45686_PWR_LOW_NOISE)) {
        return OB_ICM45686_SPI_FAILED;
    }
    imu->spi.delay_ms(imu->spi.ctx, OB_ICM45686_STARTUP_MS);
    imu->configured = true;
    return OB_ICM45686_OK;
}

static int16_t le16(const uint8_t *p) {
    return (int16_t)(uint16_t)((uint16_t)p[0] | ((uint16_t)p[1] << 8));
}

bool ob_icm45686_parse(const uint8_t data[OB_ICM45686_BURST_BYTES], ob_icm45686_sample_t *out) {
    int16_t raw[6];
    for (int i = 0; i < 6; i++) {
        raw[i] = le16(&data[2 * i]);
        if (raw[i] == OB_ICM45686_NO_DATA) {
            return false;
        }
    }
    const float accel_g_per_lsb = OB_ICM45686_ACCEL_FS_G / 32768.0f;
    const float gyro_dps_per_lsb = OB_ICM45686_GYRO_FS_DPS / 32768.0f;
    for (int i = 0; i < 3; i++) {
        out->accel_g[i] = (float)raw[i] * accel_g_per_lsb;
        out->gyro_dps[i] = (float)raw[3 + i] * gyro_dps_per_lsb;
    }
    return true;
}

bool ob_icm45686_sample(ob_icm45686_t *imu, uint32_t now_us) {
    uint8_t tx[1 + OB_ICM45686_BURST_BYTES] = {OB_ICM45686_REG_ACCEL_DATA_X1 | OB_ICM45686_READ};
    uint8_t rx[1 + OB_ICM45686_BURST_BYTES];
    ob_icm45686_sample_t sample;
    if (!imu->configured || !imu->spi.transfer(imu->spi.ctx, tx, rx, sizeof tx) || !ob_icm45686_parse(&rx[1], &sample)) {
        imu->read_errors++;
        imu->fresh = false;
        return false;
    }
    imu->last = sample;
    imu->reads_ok++;
    imu->fresh = true;
    ob_imu_yaw_update(&imu->yaw, sample.gyro_dps[2], now_us);
    return true;
}

bool ob_icm45686_read_heading(void *ctx, float *heading_deg) {
    const ob_icm45686_t *imu = ctx;
    if (!imu->fresh) {
        return false;
    }
    *heading_deg = ob_imu_yaw_heading_deg(&imu->yaw);
    return true;
}

const char *ob_icm45686_strerror(ob_icm45686_error_t error) {
    switch (error) {
    case OB_ICM45686_OK:
        return "ok";
    case OB_ICM45686_SPI_FAILED:
        return "the SPI transfer failed";
    case OB_ICM45686_NO_CHIP:
        return "WHO_AM_I (0x72) is not an ICM-45686's (0xE9)";
    }
    return "unknown ICM-45686 error";
}
