/*
 * ICM45686: the ICM-45686 core (icm45686.h) in MicroPython (host: py_icm45686.c).
 *
 * On the hub, ICM45686(sck=, mosi=, miso=, cs=) opens the SPI device
 * (mp_spi_esp32.c) and the hard tick takes one burst every millisecond, so
 * the heading integrates whatever Python is doing; a DriveBase given this
 * object as heading= reads it in C and stays on the hard tick. Elsewhere
 * (the unix port) the chip is a model behind a Python transfer(bytes) ->
 * bytes, sampled through sample(now_us), as in the host tests; or, given a
 * native SPI link as transfer= (the unix port's tests: an emulated chip in
 * C), polled by the hard tick exactly as on the hub.
 */
#include <math.h>
#include <string.h>

#include "hard_timer.h"
#include "icm45686.h"
#include "mp_bindings.h"

typedef struct {
    mp_obj_base_t base;
    ob_icm45686_t imu;
    mp_obj_t transfer; /* Python transfer(bytes) -> bytes, or MP_OBJ_NULL on the hub's SPI */
    mp_obj_t delay_ms;
    mp_obj_t error;    /* first exception of a transfer or delay callable, raised when the call ends */
    bool hardware;     /* on the hub's SPI or a native link, sampled by the hard tick */
} icm45686_obj_t;

static void stash(icm45686_obj_t *self, void *exc) {
    if (self->error == MP_OBJ_NULL) {
        self->error = MP_OBJ_FROM_PTR(exc);
    }
}

static void raise_stashed(icm45686_obj_t *self) {
    mp_obj_t error = self->error;
    if (error != MP_OBJ_NULL) {
        self->error = MP_OBJ_NULL;
        nlr_raise(error);
    }
}

static bool py_transfer(void *ctx, const uint8_t *tx, uint8_t *rx, size_t n) {
    icm45686_obj_t *self = ctx;
    nlr_buf_t nlr;
    if (nlr_push(&nlr) == 0) {
        mp_obj_t result = mp_call_function_1(self->transfer, mp_obj_new_bytes(tx, n));
        mp_buffer_info_t info;
        mp_get_buffer_raise(result, &info, MP_BUFFER_READ);
        if (info.len != n) {
            mp_raise_msg_varg(&mp_type_ValueError,
                              MP_ERROR_TEXT("ICM45686: transfer() returned %d bytes for a %d-byte transfer"),
                              (int)info.len, (int)n);
        }
        memcpy(rx, info.buf, n);
        nlr_pop();
        return true;
    }
    stash(self, nlr.ret_val);
    return false;
}

static void py_delay_ms(void *ctx, uint32_t ms) {
    icm45686_obj_t *self = ctx;
    if (self->delay_ms == MP_OBJ_NULL) {
        return; /* a register model answers at once */
    }
    nlr_buf_t nlr;
    if (nlr_push(&nlr) == 0) {
        mp_call_function_1(self->delay_ms, mp_obj_new_int_from_uint(ms));
        nlr_pop();
    } else {
        stash(self, nlr.ret_val);
    }
}

static void poll(void *ctx) {
    ob_icm45686_sample(ctx, ob_hard_timer_now_us());
}

static mp_obj_t icm45686_make_new(const mp_obj_type_t *type, size_t n_args, size_t n_kw, const mp_obj_t *all_args) {
    enum { ARG_transfer, ARG_delay_ms, ARG_scale, ARG_sck, ARG_mosi, ARG_miso, ARG_cs, ARG_hz, ARG_mode, ARG_spi_id };
    static const mp_arg_t allowed[] = {
        {MP_QSTR_transfer, MP_ARG_OBJ, {.u_obj = mp_const_none}},
        {MP_QSTR_delay_ms, MP_ARG_KW_ONLY | MP_ARG_OBJ, {.u_obj = mp_const_none}},
        {MP_QSTR_scale, MP_ARG_KW_ONLY | MP_ARG_OBJ, {.u_obj = MP_OBJ_NULL}},
        {MP_QSTR_sck, MP_ARG_KW_ONLY | MP_ARG_OBJ, {.u_obj = mp_const_none}},
        {MP_QSTR_mosi, MP_ARG_KW_ONLY | MP_ARG_OBJ, {.u_obj = mp_const_none}},
        {MP_QSTR_miso, MP_ARG_KW_ONLY | MP_ARG_OBJ, {.u_obj = mp_const_none}},
        {MP_QSTR_cs, MP_ARG_KW_ONLY | MP_ARG_OBJ, {.u_obj = mp_const_none}},
        {MP_QSTR_hz, MP_ARG_KW_ONLY | MP_ARG_INT, {.u_int = 8000000}},
        {MP_QSTR_mode, MP_ARG_KW_ONLY | MP_ARG_INT, {.u_int = 3}},
        {MP_QSTR_spi_id, MP_ARG_KW_ONLY | MP_ARG_INT, {.u_int = 1}},
    };
    mp_arg_val_t args[MP_ARRAY_SIZE(allowed)];
    mp_arg_parse_all_kw_array(n_args, n_kw, all_args, MP_ARRAY_SIZE(allowed), allowed, args);
    bool pins = false;
    for (int i = ARG_sck; i <= ARG_cs; i++) {
        pins = pins || args[i].u_obj != mp_const_none;
    }
    #if !defined(ESP_PLATFORM)
    if (pins) {
        mp_raise_msg(&mp_type_OSError, MP_ERROR_TEXT("ICM45686: this build has no SPI peripheral (only the ESP32 "
                                                     "firmware reads pins); give transfer=<callable(bytes) -> bytes>"));
    }
    #endif
    mp_obj_t transfer = args[ARG_transfer].u_obj;
    mp_obj_t delay_ms = args[ARG_delay_ms].u_obj;
    const ob_spi_t *link = ob_mp_native_spi_get(transfer);
    if (!pins && link == NULL && !mp_obj_is_callable(transfer)) {
        mp_raise_msg_varg(&mp_type_TypeError,
                          MP_ERROR_TEXT("ICM45686(): transfer must be a callable(bytes) -> bytes, got %s"),
                          mp_obj_get_type_str(transfer));
    }
    if (delay_ms != mp_const_none && !mp_obj_is_callable(delay_ms)) {
        mp_raise_msg_varg(&mp_type_TypeError, MP_ERROR_TEXT("ICM45686(): delay_ms must be a callable(ms) or None, "
                                                            "got %s"),
                          mp_obj_get_type_str(delay_ms));
    }
    ob_imu_yaw_config_t yaw_cfg;
    ob_imu_yaw_default_config(&yaw_cfg);
    if (args[ARG_scale].u_obj != MP_OBJ_NULL) {
        yaw_cfg.scale = ob_mp_float(args[ARG_scale].u_obj, "ICM45686()", "scale");
    }
    if (yaw_cfg.scale == 0.0f) {
        mp_raise_ValueError(MP_ERROR_TEXT("ICM45686(): scale must be non-zero: -1.0 for a face-up ICM-45686, "
                                          "+1.0 face-down"));
    }
    /* A finaliser: a soft reset sweeps the heap, and the hard tick must stop sampling it first. */
    icm45686_obj_t *self = mp_obj_malloc_with_finaliser(icm45686_obj_t, type);
    self->transfer = transfer;
    self->delay_ms = delay_ms == mp_const_none ? MP_OBJ_NULL : delay_ms;
    self->error = MP_OBJ_NULL;
    self->hardware = false;
    ob_spi_t spi = {py_transfer, py_delay_ms, self};
    if (link != NULL) {
        spi = *link; /* transfer keeps the link object alive */
        self->hardware = true;
    }
    #if defined(ESP_PLATFORM)
    if (pins) {
        for (int i = ARG_sck; i <= ARG_cs; i++) {
            if (args[i].u_obj == mp_const_none) {
                mp_raise_ValueError(MP_ERROR_TEXT("ICM45686: give all four SPI pins, sck=, mosi=, miso= and cs="));
            }
        }
        if (args[ARG_mode].u_int < 0 || args[ARG_mode].u_int > 3) {
            mp_raise_msg_varg(&mp_type_ValueError, MP_ERROR_TEXT("SPI mode is 0..3, got %d"), (int)args[ARG_mode].u_int);
        }
        ob_mp_spi_esp32_open((int)args[ARG_spi_id].u_int, mp_obj_get_int(args[ARG_sck].u_obj),
                             mp_obj_get_int(args[ARG_mosi].u_obj), mp_obj_get_int(args[ARG_miso].u_obj),
                             mp_obj_get_int(args[ARG_cs].u_obj), (uint32_t)args[ARG_hz].u_int, (int)args[ARG_mode].u_int,
                             &spi);
        self->hardware = true;
    }
    #endif
    ob_icm45686_init(&self->imu, &spi, &yaw_cfg);
    ob_icm45686_error_t error = ob_icm45686_configure(&self->imu);
    if (error != OB_ICM45686_OK) {
        #if defined(ESP_PLATFORM)
        if (self->hardware && link == NULL) {
            ob_mp_spi_esp32_close(&self->imu.spi);
        }
        #endif
        self->hardware = false;
    }
    raise_stashed(self);
    if (error == OB_ICM45686_NO_CHIP) {
        uint8_t who = self->imu.who_am_i;
        const char *hint = who == 0x00 || who == 0xFF ? "nothing drives MISO: check wiring and 3V3" : "another chip?";
        if (pins) {
            mp_raise_msg_varg(&mp_type_OSError,
                              MP_ERROR_TEXT("no ICM-45686 on SPI (SCK=%d MOSI=%d MISO=%d CS=%d): WHO_AM_I (0x72) reads "
                                            "0x%02X, expected 0xE9; %s"),
                              mp_obj_get_int(args[ARG_sck].u_obj), mp_obj_get_int(args[ARG_mosi].u_obj),
                              mp_obj_get_int(args[ARG_miso].u_obj), mp_obj_get_int(args[ARG_cs].u_obj), (unsigned)who,
                              hint);
        }
        mp_raise_msg_varg(&mp_type_OSError,
                          MP_ERROR_TEXT("no ICM-45686 on SPI: WHO_AM_I (0x72) reads 0x%02X, expected 0xE9; %s"),
                          (unsigned)who, hint);
    }
    if (error != OB_ICM45686_OK) {
        mp_raise_msg_varg(&mp_type_OSError, MP_ERROR_TEXT("ICM45686: %s"), ob_icm45686_strerror(error));
    }
    if (self->hardware) {
        ob_mp_hard_tick_poll(MP_OBJ_FROM_PTR(self), poll, &self->imu);
    }
    return MP_OBJ_FROM_PTR(self);
}

static mp_obj_t icm45686_sample(mp_obj_t self_in, mp_obj_t now_in) {
    icm45686_obj_t *self = MP_OBJ_TO_PTR(self_in);
    if (!mp_obj_is_int(now_in)) {
        mp_raise_msg_varg(&mp_type_TypeError,
                          MP_ERROR_TEXT("ICM45686.sample(): now_us must be an int (microseconds), not %s"),
                          mp_obj_get_type_str(now_in));
    }
    bool ok = ob_icm45686_sample(&self->imu, (uint32_t)mp_obj_get_int_truncated(now_in));
    raise_stashed(self);
    return mp_obj_new_bool(ok);
}
static MP_DEFINE_CONST_FUN_OBJ_2(icm45686_sample_obj, icm45686_sample);

static mp_obj_t icm45686_heading(mp_obj_t self_in) {
    icm45686_obj_t *self = MP_OBJ_TO_PTR(self_in);
    return mp_obj_new_float(ob_imu_yaw_heading_deg(&self->imu.yaw));
}
static MP_DEFINE_CONST_FUN_OBJ_1(icm45686_heading_obj, icm45686_heading);

static mp_obj_t icm45686_rate(mp_obj_t self_in) {
    icm45686_obj_t *self = MP_OBJ_TO_PTR(self_in);
    return mp_obj_new_float(ob_imu_yaw_rate_dps(&self->imu.yaw));
}
static MP_DEFINE_CONST_FUN_OBJ_1(icm45686_rate_obj, icm45686_rate);

static mp_obj_t icm45686_bias(mp_obj_t self_in) {
    icm45686_obj_t *self = MP_OBJ_TO_PTR(self_in);
    return mp_obj_new_float(ob_imu_yaw_bias_dps(&self->imu.yaw));
}
static MP_DEFINE_CONST_FUN_OBJ_1(icm45686_bias_obj, icm45686_bias);

static mp_obj_t icm45686_calibrated(mp_obj_t self_in) {
    icm45686_obj_t *self = MP_OBJ_TO_PTR(self_in);
    return mp_obj_new_bool(ob_imu_yaw_calibrated(&self->imu.yaw));
}
static MP_DEFINE_CONST_FUN_OBJ_1(icm45686_calibrated_obj, icm45686_calibrated);

static mp_obj_t icm45686_reset_heading(size_t n_args, const mp_obj_t *args) {
    icm45686_obj_t *self = MP_OBJ_TO_PTR(args[0]);
    float heading = n_args > 1 ? ob_mp_float(args[1], "ICM45686.reset_heading()", "heading") : 0.0f;
    ob_imu_yaw_reset_heading(&self->imu.yaw, heading);
    return mp_const_none;
}
static MP_DEFINE_CONST_FUN_OBJ_VAR_BETWEEN(icm45686_reset_heading_obj, 1, 2, icm45686_reset_heading);

static mp_obj_t icm45686_seed_bias(mp_obj_t self_in, mp_obj_t bias_in) {
    icm45686_obj_t *self = MP_OBJ_TO_PTR(self_in);
    mp_float_t bias;
    if (bias_in == mp_const_true || bias_in == mp_const_false || !mp_obj_get_float_maybe(bias_in, &bias)) {
        mp_raise_msg_varg(&mp_type_TypeError, MP_ERROR_TEXT("bias_dps must be a number, not %s"),
                          mp_obj_get_type_str(bias_in));
    }
    if (!ob_imu_yaw_seed_bias(&self->imu.yaw, (float)bias)) {
        mp_raise_msg_varg(&mp_type_ValueError,
                          MP_ERROR_TEXT("seed_bias(%g): a gyro bias must be finite and within +-%g deg/s "
                                        "(max_bias_dps); the stored calibration looks corrupt, recalibrate at rest"),
                          (double)bias, (double)self->imu.yaw.cfg.max_bias_dps);
    }
    return mp_const_none;
}
static MP_DEFINE_CONST_FUN_OBJ_2(icm45686_seed_bias_obj, icm45686_seed_bias);

static mp_obj_t triple(const float *v) {
    mp_obj_t items[3] = {mp_obj_new_float(v[0]), mp_obj_new_float(v[1]), mp_obj_new_float(v[2])};
    return mp_obj_new_tuple(3, items);
}

static mp_obj_t icm45686_gyro(mp_obj_t self_in) {
    icm45686_obj_t *self = MP_OBJ_TO_PTR(self_in);
    return triple(self->imu.last.gyro_dps);
}
static MP_DEFINE_CONST_FUN_OBJ_1(icm45686_gyro_obj, icm45686_gyro);

static mp_obj_t icm45686_acceleration(mp_obj_t self_in) {
    icm45686_obj_t *self = MP_OBJ_TO_PTR(self_in);
    return triple(self->imu.last.accel_g);
}
static MP_DEFINE_CONST_FUN_OBJ_1(icm45686_acceleration_obj, icm45686_acceleration);

static mp_obj_t icm45686_stats(mp_obj_t self_in) {
    icm45686_obj_t *self = MP_OBJ_TO_PTR(self_in);
    mp_obj_t items[3] = {mp_obj_new_int_from_uint(self->imu.reads_ok), mp_obj_new_int_from_uint(self->imu.read_errors),
                         mp_obj_new_bool(self->imu.configured)};
    return mp_obj_new_tuple(3, items);
}
static MP_DEFINE_CONST_FUN_OBJ_1(icm45686_stats_obj, icm45686_stats);

static mp_obj_t icm45686_close(mp_obj_t self_in) {
    icm45686_obj_t *self = MP_OBJ_TO_PTR(self_in);
    if (self->hardware) {
        ob_mp_hard_tick_unpoll(&self->imu);
        #if defined(ESP_PLATFORM)
        if (ob_mp_native_spi_get(self->transfer) == NULL) {
            ob_mp_spi_esp32_close(&self->imu.spi);
        }
        #endif
        self->hardware = false;
    }
    self->imu.configured = false; /* later samples fail */
    return mp_const_none;
}
static MP_DEFINE_CONST_FUN_OBJ_1(icm45686_close_obj, icm45686_close);

static const mp_rom_map_elem_t icm45686_locals_table[] = {
    {MP_ROM_QSTR(MP_QSTR_sample), MP_ROM_PTR(&icm45686_sample_obj)},
    {MP_ROM_QSTR(MP_QSTR_heading), MP_ROM_PTR(&icm45686_heading_obj)},
    {MP_ROM_QSTR(MP_QSTR_rate), MP_ROM_PTR(&icm45686_rate_obj)},
    {MP_ROM_QSTR(MP_QSTR_bias), MP_ROM_PTR(&icm45686_bias_obj)},
    {MP_ROM_QSTR(MP_QSTR_calibrated), MP_ROM_PTR(&icm45686_calibrated_obj)},
    {MP_ROM_QSTR(MP_QSTR_reset_heading), MP_ROM_PTR(&icm45686_reset_heading_obj)},
    {MP_ROM_QSTR(MP_QSTR_seed_bias), MP_ROM_PTR(&icm45686_seed_bias_obj)},
    {MP_ROM_QSTR(MP_QSTR_gyro), MP_ROM_PTR(&icm45686_gyro_obj)},
    {MP_ROM_QSTR(MP_QSTR_acceleration), MP_ROM_PTR(&icm45686_acceleration_obj)},
    {MP_ROM_QSTR(MP_QSTR_stats), MP_ROM_PTR(&icm45686_stats_obj)},
    {MP_ROM_QSTR(MP_QSTR_close), MP_ROM_PTR(&icm45686_close_obj)},
    {MP_ROM_QSTR(MP_QSTR___del__), MP_ROM_PTR(&icm45686_close_obj)},
    #if defined(ESP_PLATFORM)
    {MP_ROM_QSTR(MP_QSTR_HARDWARE), MP_ROM_TRUE},
    #else
    {MP_ROM_QSTR(MP_QSTR_HARDWARE), MP_ROM_FALSE},
    #endif
};
static MP_DEFINE_CONST_DICT(icm45686_locals, icm45686_locals_table);

/* Methods run under the motor lock: the hard tick samples the same IMU from its own context. */
static void icm45686_attr(mp_obj_t self_in, qstr attr, mp_obj_t *dest) {
    ob_mp_locked_attr(self_in, attr, dest, &icm45686_locals);
}

MP_DEFINE_CONST_OBJ_TYPE(
    ob_mp_icm45686_type,
    MP_QSTR_ICM45686,
    MP_TYPE_FLAG_NONE,
    make_new, icm45686_make_new,
    attr, icm45686_attr,
    locals_dict, &icm45686_locals
    );

bool ob_mp_icm45686_heading_source(mp_obj_t obj, ob_heading_source_t *source) {
    if (!mp_obj_is_type(obj, &ob_mp_icm45686_type)) {
        return false;
    }
    icm45686_obj_t *self = MP_OBJ_TO_PTR(obj);
    source->read_heading = ob_icm45686_read_heading;
    source->ctx = &self->imu;
    return true;
}
