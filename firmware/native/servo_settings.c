/*
 * The servo's settings table and the messages that refuse a value: see servo_settings.h.
 */
#include "servo_settings.h"

#include <stdio.h>
#include <string.h>

#define CFG(field) offsetof(ob_servo_config_t, field)
#define BIG 3.0e38f
#define MS_MAX 4.0e9f

const ob_servo_setting_t ob_servo_settings[OB_SERVO_SETTINGS_COUNT] = {
    {"kp", CFG(kp_pct_per_deg), false, 0.0f, false, BIG},
    {"ki", CFG(ki_pct_per_deg_s), false, 0.0f, false, BIG},
    {"kd", CFG(kd_pct_per_dps), false, 0.0f, false, BIG},
    {"integral_band_deg", CFG(integral_band_deg), false, 0.0f, false, BIG},
    {"integral_limit_pct", CFG(integral_limit_pct), false, 0.0f, false, 100.0f},
    {"speed_kp", CFG(speed_kp_pct_per_dps), false, 0.0f, false, BIG},
    {"speed_ki", CFG(speed_ki_pct_per_deg), false, 0.0f, false, BIG},
    {"ff_speed", CFG(ff_pct_per_dps), false, 0.0f, false, BIG},
    {"ff_accel", CFG(ff_pct_per_dps2), false, 0.0f, false, BIG},
    {"ff_static", CFG(ff_static_pct), false, 0.0f, false, 100.0f},
    {"max_speed_dps", CFG(max_speed_dps), false, 0.0f, true, BIG},
    {"accel_dps2", CFG(accel_dps2), false, 0.0f, true, BIG},
    {"decel_dps2", CFG(decel_dps2), false, 0.0f, true, BIG},
    {"position_tolerance_deg", CFG(position_tolerance_deg), false, 0.0f, true, BIG},
    {"speed_tolerance_dps", CFG(speed_tolerance_dps), false, 0.0f, true, BIG},
    {"stall_error_deg", CFG(stall_error_deg), false, 0.0f, true, BIG},
    {"stall_speed_dps", CFG(stall_speed_dps), false, 0.0f, true, BIG},
    {"stall_time_ms", CFG(stall_time_ms), true, 0.0f, false, MS_MAX},
    {"silent_timeout_ms", CFG(silent_timeout_ms), true, 1.0f, false, MS_MAX},
    {"counts_per_rev", CFG(counts_per_rev), false, 0.0f, true, BIG},
    {"observer_alpha", CFG(observer_alpha), false, 0.0f, true, 1.0f},
    {"observer_beta", CFG(observer_beta), false, 0.0f, true, 1.0f},
};

/* "kp, ki, ..." for the unknown-name message, in the table's order. */
static void list_names(char *out, size_t size) {
    size_t used = 0;
    out[0] = '\0';
    for (size_t i = 0; i < OB_SERVO_SETTINGS_COUNT && used < size; i++) {
        int n = snprintf(out + used, size - used, "%s%s", i == 0 ? "" : ", ", ob_servo_settings[i].name);
        used += n > 0 ? (size_t)n : 0u;
    }
}

const ob_servo_setting_t *ob_servo_setting_find(const char *name, const char *where, char *msg, size_t msg_size) {
    for (size_t i = 0; i < OB_SERVO_SETTINGS_COUNT; i++) {
        if (strcmp(ob_servo_settings[i].name, name) == 0) {
            return &ob_servo_settings[i];
        }
    }
    char names[360];
    list_names(names, sizeof(names));
    snprintf(msg, msg_size, "%s: unknown setting '%s'; the settings are: %s", where, name, names);
    return NULL;
}

ob_setting_status_t ob_servo_setting_set(ob_servo_config_t *cfg, const ob_servo_setting_t *setting, double value,
                                         bool is_int, const char *type_name, const char *where, char *msg,
                                         size_t msg_size) {
    if (setting->is_ms && !is_int) {
        snprintf(msg, msg_size, "%s: %s must be an int (milliseconds), not %s", where, setting->name, type_name);
        return OB_SETTING_TYPE_ERROR;
    }
    double min = (double)setting->min;
    bool low = setting->min_open ? !(value > min) : value < min;
    if (low || value > (double)setting->max) {
        snprintf(msg, msg_size, "%s: %s must be %s %g, got %g", where, setting->name,
                 low ? (setting->min_open ? ">" : ">=") : "<=", (double)(low ? setting->min : setting->max), value);
        return OB_SETTING_VALUE_ERROR;
    }
    char *field = (char *)cfg + setting->offset;
    if (setting->is_ms) {
        *(uint32_t *)field = (uint32_t)value;
    } else {
        *(float *)field = (float)value;
    }
    return OB_SETTING_OK;
}

double ob_servo_setting_get(const ob_servo_config_t *cfg, const ob_servo_setting_t *setting) {
    const char *field = (const char *)cfg + setting->offset;
    return setting->is_ms ? (double)*(const uint32_t *)field : (double)*(const float *)field;
}

bool ob_servo_duty_limit_valid(float limit_pct, const char *where, const char *name, const char *note, char *msg,
                               size_t msg_size) {
    if (limit_pct > 0.0f && limit_pct <= 100.0f) {
        return true;
    }
    snprintf(msg, msg_size, "%s: %s must be within (0, 100] percent%s, got %g", where, name, note, (double)limit_pct);
    return false;
}

const char *ob_servo_mode_name(ob_servo_mode_t mode) {
    switch (mode) {
    case OB_SERVO_BRAKE:
        return "brake";
    case OB_SERVO_DUTY:
        return "dc";
    case OB_SERVO_SPEED:
        return "speed";
    case OB_SERVO_POSITION:
        return "position";
    case OB_SERVO_COAST:
    default:
        return "coast";
    }
}
