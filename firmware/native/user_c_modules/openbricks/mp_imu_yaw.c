/*
 * ImuYaw: the gyro heading integrator (host: py_imu_yaw.c).
 */
#include <math.h>

#include "imu_yaw.h"
#include "mp_bindings.h"

/* Longest settle window accepted: a minute of stillness is already far more than any robot waits. */
#define SETTLE_MS_MAX 60000.0f

typedef struct {
    mp_obj_base_t base;
    ob_imu_yaw_t yaw;
} imu_yaw_obj_t;

static float ranged(mp_obj_t obj, const char *name, float lo, float hi) {
    float value = ob_mp_float(obj, "ImuYaw", name);
    if (value < lo || value > hi) {
        mp_raise_msg_varg(&mp_type_ValueError, MP_ERROR_TEXT("%s must be in %g..%g, got %g"), name, (double)lo,
                          (double)hi, (double)value);
    }
    return value;
}

static mp_obj_t imu_yaw_make_new(const mp_obj_type_t *type, size_t n_args, size_t n_kw, const mp_obj_t *all_args) {
    enum { ARG_scale, ARG_still_band_dps, ARG_settle_ms, ARG_track_tau_s, ARG_max_bias_dps };
    static const mp_arg_t allowed[] = {
        {MP_QSTR_scale, MP_ARG_KW_ONLY | MP_ARG_OBJ, {.u_obj = MP_OBJ_NULL}},
        {MP_QSTR_still_band_dps, MP_ARG_KW_ONLY | MP_ARG_OBJ, {.u_obj = MP_OBJ_NULL}},
        {MP_QSTR_settle_ms, MP_ARG_KW_ONLY | MP_ARG_OBJ, {.u_obj = MP_OBJ_NULL}},
        {MP_QSTR_track_tau_s, MP_ARG_KW_ONLY | MP_ARG_OBJ, {.u_obj = MP_OBJ_NULL}},
        {MP_QSTR_max_bias_dps, MP_ARG_KW_ONLY | MP_ARG_OBJ, {.u_obj = MP_OBJ_NULL}},
    };
    mp_arg_val_t args[MP_ARRAY_SIZE(allowed)];
    mp_arg_parse_all_kw_array(n_args, n_kw, all_args, MP_ARRAY_SIZE(allowed), allowed, args);
    ob_imu_yaw_config_t cfg;
    ob_imu_yaw_default_config(&cfg);
    if (args[ARG_scale].u_obj != MP_OBJ_NULL) {
        cfg.scale = ob_mp_float(args[ARG_scale].u_obj, "ImuYaw", "scale");
        if (cfg.scale == 0.0f) {
            mp_raise_ValueError(MP_ERROR_TEXT("scale must be non-zero (-1 for a face-up gyro, +1 for face-down)"));
        }
    }
    if (args[ARG_still_band_dps].u_obj != MP_OBJ_NULL) {
        cfg.still_band_dps = ranged(args[ARG_still_band_dps].u_obj, "still_band_dps", 1e-6f, 1e3f);
    }
    if (args[ARG_settle_ms].u_obj != MP_OBJ_NULL) {
        cfg.settle_us = (uint32_t)(ranged(args[ARG_settle_ms].u_obj, "settle_ms", 0.0f, SETTLE_MS_MAX) * 1000.0f + 0.5f);
    }
    if (args[ARG_track_tau_s].u_obj != MP_OBJ_NULL) {
        cfg.track_tau_s = ranged(args[ARG_track_tau_s].u_obj, "track_tau_s", 1e-3f, 1e6f);
    }
    if (args[ARG_max_bias_dps].u_obj != MP_OBJ_NULL) {
        cfg.max_bias_dps = ranged(args[ARG_max_bias_dps].u_obj, "max_bias_dps", 1e-6f, 1e3f);
    }
    imu_yaw_obj_t *self = mp_obj_malloc(imu_yaw_obj_t, type);
    ob_imu_yaw_init(&self->yaw, &cfg);
    return MP_OBJ_FROM_PTR(self);
}

static mp_obj_t imu_yaw_update(mp_obj_t self_in, mp_obj_t gyro_in, mp_obj_t now_in) {
    imu_yaw_obj_t *self = MP_OBJ_TO_PTR(self_in);
    mp_float_t gyro_z_dps;
    if (gyro_in == mp_const_true || gyro_in == mp_const_false || !mp_obj_get_float_maybe(gyro_in, &gyro_z_dps)) {
        mp_raise_msg_varg(&mp_type_TypeError, MP_ERROR_TEXT("gyro_z_dps must be a number, not %s"),
                          mp_obj_get_type_str(gyro_in));
    }
    if (!mp_obj_is_int(now_in)) {
        mp_raise_msg_varg(&mp_type_TypeError, MP_ERROR_TEXT("now_us must be an int (microseconds), not %s"),
                          mp_obj_get_type_str(now_in));
    }
    /* Only differences matter, so any integer clock works modulo 2**32, like the hub's. A NaN rate is
     * passed on: the core drops it like a missed sample. */
    ob_imu_yaw_update(&self->yaw, (float)gyro_z_dps, (uint32_t)mp_obj_get_int_truncated(now_in));
    return mp_const_none;
}
static MP_DEFINE_CONST_FUN_OBJ_3(imu_yaw_update_obj, imu_yaw_update);

static mp_obj_t imu_yaw_heading(mp_obj_t self_in) {
    imu_yaw_obj_t *self = MP_OBJ_TO_PTR(self_in);
    return mp_obj_new_float(ob_imu_yaw_heading_deg(&self->yaw));
}
static MP_DEFINE_CONST_FUN_OBJ_1(imu_yaw_heading_obj, imu_yaw_heading);

static mp_obj_t imu_yaw_rate(mp_obj_t self_in) {
    imu_yaw_obj_t *self = MP_OBJ_TO_PTR(self_in);
    return mp_obj_new_float(ob_imu_yaw_rate_dps(&self->yaw));
}
static MP_DEFINE_CONST_FUN_OBJ_1(imu_yaw_rate_obj, imu_yaw_rate);

static mp_obj_t imu_yaw_bias(mp_obj_t self_in) {
    imu_yaw_obj_t *self = MP_OBJ_TO_PTR(self_in);
    return mp_obj_new_float(ob_imu_yaw_bias_dps(&self->yaw));
}
static MP_DEFINE_CONST_FUN_OBJ_1(imu_yaw_bias_obj, imu_yaw_bias);

static mp_obj_t imu_yaw_calibrated(mp_obj_t self_in) {
    imu_yaw_obj_t *self = MP_OBJ_TO_PTR(self_in);
    return mp_obj_new_bool(ob_imu_yaw_calibrated(&self->yaw));
}
static MP_DEFINE_CONST_FUN_OBJ_1(imu_yaw_calibrated_obj, imu_yaw_calibrated);

static mp_obj_t imu_yaw_reset_heading(size_t n_args, const mp_obj_t *args) {
    imu_yaw_obj_t *self = MP_OBJ_TO_PTR(args[0]);
    float heading = n_args > 1 ? ob_mp_float(args[1], "ImuYaw.reset_heading", "heading") : 0.0f;
    ob_imu_yaw_reset_heading(&self->yaw, heading);
    return mp_const_none;
}
static MP_DEFINE_CONST_FUN_OBJ_VAR_BETWEEN(imu_yaw_reset_heading_obj, 1, 2, imu_yaw_reset_heading);

static mp_obj_t imu_yaw_seed_bias(mp_obj_t self_in, mp_obj_t bias_in) {
    imu_yaw_obj_t *self = MP_OBJ_TO_PTR(self_in);
    mp_float_t bias;
    if (bias_in == mp_const_true || bias_in == mp_const_false || !mp_obj_get_float_maybe(bias_in, &bias)) {
        mp_raise_msg_varg(&mp_type_TypeError, MP_ERROR_TEXT("bias_dps must be a number, not %s"),
                          mp_obj_get_type_str(bias_in));
    }
    if (!ob_imu_yaw_seed_bias(&self->yaw, (float)bias)) {
        mp_raise_msg_varg(&mp_type_ValueError,
                          MP_ERROR_TEXT("seed_bias(%g): a gyro bias must be finite and within +-%g deg/s "
                                        "(max_bias_dps); the stored calibration looks corrupt, recalibrate at rest"),
                          (double)bias, (double)self->yaw.cfg.max_bias_dps);
    }
    return mp_const_none;
}
static MP_DEFINE_CONST_FUN_OBJ_2(imu_yaw_seed_bias_obj, imu_yaw_seed_bias);

static const mp_rom_map_elem_t imu_yaw_locals_table[] = {
    {MP_ROM_QSTR(MP_QSTR_update), MP_ROM_PTR(&imu_yaw_update_obj)},
    {MP_ROM_QSTR(MP_QSTR_heading), MP_ROM_PTR(&imu_yaw_heading_obj)},
    {MP_ROM_QSTR(MP_QSTR_rate), MP_ROM_PTR(&imu_yaw_rate_obj)},
    {MP_ROM_QSTR(MP_QSTR_bias), MP_ROM_PTR(&imu_yaw_bias_obj)},
    {MP_ROM_QSTR(MP_QSTR_calibrated), MP_ROM_PTR(&imu_yaw_calibrated_obj)},
    {MP_ROM_QSTR(MP_QSTR_reset_heading), MP_ROM_PTR(&imu_yaw_reset_heading_obj)},
    {MP_ROM_QSTR(MP_QSTR_seed_bias), MP_ROM_PTR(&imu_yaw_seed_bias_obj)},
};
static MP_DEFINE_CONST_DICT(imu_yaw_locals, imu_yaw_locals_table);

MP_DEFINE_CONST_OBJ_TYPE(
    ob_mp_imu_yaw_type,
    MP_QSTR_ImuYaw,
    MP_TYPE_FLAG_NONE,
    make_new, imu_yaw_make_new,
    locals_dict, &imu_yaw_locals
    );
