/*
 * HBridge: the H-bridge core (hbridge.h) in MicroPython (host: py_hbridge.c).
 *
 * On the hub, HBridge(in1, in2, pwm, invert=, freq_hz=) drives IN1/IN2 as
 * GPIO and EN on an LEDC channel (mp_hbridge_esp32.c). outputs= takes any
 * native pin set instead (the unix port's tests: an emulated DC motor in C).
 * Without either, the core only keeps the levels, which levels() reports.
 *
 * motor_io(encoder, deg_per_count) joins the bridge with a PCNTEncoder into
 * a MotorIO whose functions never call Python (dc_motor_io.h): a Servo(io=)
 * or DriveBase(left_io=, right_io=) over it is hard-safe, so the hard tick
 * runs a DC drive base's whole loop in C, as it runs a serial-bus one.
 * Methods run under the motor lock: the hard tick writes the same pins.
 */
#include <string.h>

#include "dc_motor_io.h"
#include "hbridge.h"
#include "mp_bindings.h"

typedef struct {
    mp_obj_base_t base;
    ob_hbridge_t hb;
    bool closed;
    bool hardware;   /* the hub's GPIO and LEDC channel, given back on close */
    mp_obj_t outputs; /* the native pin set driven (kept alive), or MP_OBJ_NULL */
} hbridge_obj_t;

/* A DC motor's IO: a MotorIO over the bridge and an encoder core, both kept alive by it. */
typedef struct {
    ob_mp_motor_io_t base;
    ob_dc_motor_io_t dc;
    mp_obj_t bridge;
    mp_obj_t encoder;
} dc_io_obj_t;

static const mp_obj_type_t dc_io_type;

static mp_obj_t hbridge_make_new(const mp_obj_type_t *type, size_t n_args, size_t n_kw, const mp_obj_t *all_args) {
    enum { ARG_in1, ARG_in2, ARG_pwm, ARG_invert, ARG_freq_hz, ARG_outputs };
    static const mp_arg_t allowed[] = {
        {MP_QSTR_in1, MP_ARG_OBJ, {.u_obj = mp_const_none}},
        {MP_QSTR_in2, MP_ARG_OBJ, {.u_obj = mp_const_none}},
        {MP_QSTR_pwm, MP_ARG_OBJ, {.u_obj = mp_const_none}},
        {MP_QSTR_invert, MP_ARG_KW_ONLY | MP_ARG_BOOL, {.u_bool = false}},
        {MP_QSTR_freq_hz, MP_ARG_KW_ONLY | MP_ARG_OBJ, {.u_obj = MP_OBJ_NULL}},
        {MP_QSTR_outputs, MP_ARG_KW_ONLY | MP_ARG_OBJ, {.u_obj = mp_const_none}},
    };
    mp_arg_val_t args[MP_ARRAY_SIZE(allowed)];
    mp_arg_parse_all_kw_array(n_args, n_kw, all_args, MP_ARRAY_SIZE(allowed), allowed, args);
    int n_pins = (args[ARG_in1].u_obj != mp_const_none) + (args[ARG_in2].u_obj != mp_const_none) +
                 (args[ARG_pwm].u_obj != mp_const_none);
    if (n_pins != 0 && n_pins != 3) {
        mp_raise_ValueError(MP_ERROR_TEXT("HBridge(): give all three pins, in1, in2 and pwm, or none"));
    }
    #if !defined(ESP_PLATFORM)
    if (n_pins != 0) {
        mp_raise_msg(&mp_type_OSError, MP_ERROR_TEXT("HBridge: this build has no LEDC peripheral (only the ESP32 "
                                                     "firmware drives pins); leave the pins out, or pass outputs="));
    }
    #endif
    ob_hbridge_config_t cfg;
    ob_hbridge_default_config(&cfg, OB_HBRIDGE_DEFAULT_FREQ_HZ);
    cfg.invert = args[ARG_invert].u_bool;
    if (args[ARG_freq_hz].u_obj != MP_OBJ_NULL) {
        int32_t freq = ob_mp_int32(args[ARG_freq_hz].u_obj, "HBridge()", "freq_hz");
        cfg.freq_hz = freq < 0 ? 0u : (uint32_t)freq;
    }
    ob_hbridge_error_t error = ob_hbridge_check_config(&cfg);
    if (error != OB_HBRIDGE_OK) {
        mp_raise_msg_varg(&mp_type_ValueError, MP_ERROR_TEXT("HBridge(): %s"), ob_hbridge_strerror(error));
    }
    const ob_hbridge_pins_t *outputs = NULL;
    if (args[ARG_outputs].u_obj != mp_const_none) {
        outputs = ob_mp_native_hbridge_pins_get(args[ARG_outputs].u_obj);
        if (outputs == NULL || n_pins != 0) {
            mp_raise_TypeError(MP_ERROR_TEXT("HBridge(): outputs= takes a native H-bridge pin set (not with "
                                             "in1/in2/pwm)"));
        }
    }
    /* A finaliser: a soft reset sweeps the heap, and the LEDC channel must be given back first. */
    hbridge_obj_t *self = mp_obj_malloc_with_finaliser(hbridge_obj_t, type);
    self->closed = false;
    self->hardware = false;
    self->outputs = MP_OBJ_NULL;
    ob_hbridge_pins_t pins = {NULL, 0u, NULL};
    if (outputs != NULL) {
        pins = *outputs;
        self->outputs = args[ARG_outputs].u_obj;
    }
    #if defined(ESP_PLATFORM)
    if (n_pins == 3) {
        ob_mp_hbridge_esp32_open(mp_obj_get_int(args[ARG_in1].u_obj), mp_obj_get_int(args[ARG_in2].u_obj),
                                 mp_obj_get_int(args[ARG_pwm].u_obj), cfg.freq_hz, &pins);
        self->hardware = true;
    }
    #endif
    error = ob_hbridge_init(&self->hb, &cfg, &pins);
    if (error != OB_HBRIDGE_OK) {
        #if defined(ESP_PLATFORM)
        if (self->hardware) {
            ob_mp_hbridge_esp32_close(&pins);
        }
        #endif
        self->closed = true;
        mp_raise_msg_varg(&mp_type_ValueError, MP_ERROR_TEXT("HBridge(): %s"), ob_hbridge_strerror(error));
    }
    return MP_OBJ_FROM_PTR(self);
}

static hbridge_obj_t *open_self(mp_obj_t self_in, const char *method) {
    hbridge_obj_t *self = MP_OBJ_TO_PTR(self_in);
    if (self->closed) {
        mp_raise_msg_varg(&mp_type_ValueError, MP_ERROR_TEXT("HBridge.%s(): the bridge was closed; construct a "
                                                             "new one"),
                          method);
    }
    return self;
}

static mp_obj_t hbridge_drive(mp_obj_t self_in, mp_obj_t duty_in) {
    hbridge_obj_t *self = open_self(self_in, "drive");
    ob_hbridge_drive(&self->hb, ob_mp_float(duty_in, "HBridge.drive()", "duty_pct"));
    return mp_const_none;
}
static MP_DEFINE_CONST_FUN_OBJ_2(hbridge_drive_obj, hbridge_drive);

static mp_obj_t hbridge_brake(mp_obj_t self_in) {
    ob_hbridge_brake(&open_self(self_in, "brake")->hb);
    return mp_const_none;
}
static MP_DEFINE_CONST_FUN_OBJ_1(hbridge_brake_obj, hbridge_brake);

static mp_obj_t hbridge_coast(mp_obj_t self_in) {
    ob_hbridge_coast(&open_self(self_in, "coast")->hb);
    return mp_const_none;
}
static MP_DEFINE_CONST_FUN_OBJ_1(hbridge_coast_obj, hbridge_coast);

static mp_obj_t hbridge_levels(mp_obj_t self_in) {
    hbridge_obj_t *self = MP_OBJ_TO_PTR(self_in);
    mp_obj_t items[4] = {
        mp_obj_new_bool(self->hb.levels.in1),
        mp_obj_new_bool(self->hb.levels.in2),
        mp_obj_new_int_from_uint(self->hb.levels.duty),
        mp_obj_new_int_from_uint(ob_hbridge_duty_max(&self->hb)),
    };
    return mp_obj_new_tuple(4, items);
}
static MP_DEFINE_CONST_FUN_OBJ_1(hbridge_levels_obj, hbridge_levels);

static mp_obj_t hbridge_duty(mp_obj_t self_in) {
    return mp_obj_new_float(((hbridge_obj_t *)MP_OBJ_TO_PTR(self_in))->hb.duty_pct);
}
static MP_DEFINE_CONST_FUN_OBJ_1(hbridge_duty_obj, hbridge_duty);

static mp_obj_t hbridge_state(mp_obj_t self_in) {
    const char *name = ob_hbridge_state_name(((hbridge_obj_t *)MP_OBJ_TO_PTR(self_in))->hb.state);
    return mp_obj_new_str(name, strlen(name));
}
static MP_DEFINE_CONST_FUN_OBJ_1(hbridge_state_obj, hbridge_state);

static mp_obj_t hbridge_stats(mp_obj_t self_in) {
    hbridge_obj_t *self = MP_OBJ_TO_PTR(self_in);
    mp_obj_t items[2] = {mp_obj_new_int_from_uint(self->hb.writes), mp_obj_new_int_from_uint(self->hb.write_errors)};
    return mp_obj_new_tuple(2, items);
}
static MP_DEFINE_CONST_FUN_OBJ_1(hbridge_stats_obj, hbridge_stats);

static mp_obj_t hbridge_motor_io(mp_obj_t self_in, mp_obj_t encoder_in, mp_obj_t deg_per_count_in) {
    hbridge_obj_t *self = open_self(self_in, "motor_io");
    ob_encoder_t *encoder = ob_mp_pcnt_encoder_get(encoder_in);
    if (encoder == NULL) {
        mp_raise_msg_varg(&mp_type_TypeError,
                          MP_ERROR_TEXT("HBridge.motor_io(): encoder must be an open PCNTEncoder, not %s"),
                          mp_obj_get_type_str(encoder_in));
    }
    ob_mp_positive_float(deg_per_count_in, "HBridge.motor_io()", "deg_per_count");
    dc_io_obj_t *io = mp_obj_malloc(dc_io_obj_t, &dc_io_type);
    /* Read again at the interpreter's width: a float would round 360 / 68028 in the sixth digit. */
    ob_dc_motor_io_init(&io->dc, encoder, &self->hb, (double)mp_obj_get_float(deg_per_count_in));
    io->base.io = ob_dc_motor_io(&io->dc);
    io->bridge = self_in;
    io->encoder = encoder_in;
    return MP_OBJ_FROM_PTR(io);
}
static MP_DEFINE_CONST_FUN_OBJ_3(hbridge_motor_io_obj, hbridge_motor_io);

static mp_obj_t hbridge_close(mp_obj_t self_in) {
    hbridge_obj_t *self = MP_OBJ_TO_PTR(self_in);
    if (self->closed) {
        return mp_const_none;
    }
    ob_hbridge_pins_t pins = self->hb.pins;
    /* Coasted and unwired: a controller still holding this bridge's motor IO writes nowhere. */
    ob_hbridge_unwire(&self->hb);
    #if defined(ESP_PLATFORM)
    if (self->hardware) {
        ob_mp_hbridge_esp32_close(&pins);
    }
    #else
    (void)pins;
    #endif
    self->hardware = false;
    self->outputs = MP_OBJ_NULL;
    self->closed = true;
    return mp_const_none;
}
static MP_DEFINE_CONST_FUN_OBJ_1(hbridge_close_obj, hbridge_close);

static const mp_rom_map_elem_t hbridge_locals_table[] = {
    {MP_ROM_QSTR(MP_QSTR_drive), MP_ROM_PTR(&hbridge_drive_obj)},
    {MP_ROM_QSTR(MP_QSTR_brake), MP_ROM_PTR(&hbridge_brake_obj)},
    {MP_ROM_QSTR(MP_QSTR_coast), MP_ROM_PTR(&hbridge_coast_obj)},
    {MP_ROM_QSTR(MP_QSTR_levels), MP_ROM_PTR(&hbridge_levels_obj)},
    {MP_ROM_QSTR(MP_QSTR_duty), MP_ROM_PTR(&hbridge_duty_obj)},
    {MP_ROM_QSTR(MP_QSTR_state), MP_ROM_PTR(&hbridge_state_obj)},
    {MP_ROM_QSTR(MP_QSTR_stats), MP_ROM_PTR(&hbridge_stats_obj)},
    {MP_ROM_QSTR(MP_QSTR_motor_io), MP_ROM_PTR(&hbridge_motor_io_obj)},
    {MP_ROM_QSTR(MP_QSTR_close), MP_ROM_PTR(&hbridge_close_obj)},
    {MP_ROM_QSTR(MP_QSTR___del__), MP_ROM_PTR(&hbridge_close_obj)},
    #if defined(ESP_PLATFORM)
    {MP_ROM_QSTR(MP_QSTR_HARDWARE), MP_ROM_TRUE},
    #else
    {MP_ROM_QSTR(MP_QSTR_HARDWARE), MP_ROM_FALSE},
    #endif
};
static MP_DEFINE_CONST_DICT(hbridge_locals, hbridge_locals_table);

static void hbridge_attr(mp_obj_t self_in, qstr attr, mp_obj_t *dest) {
    ob_mp_locked_attr(self_in, attr, dest, &hbridge_locals);
}

MP_DEFINE_CONST_OBJ_TYPE(
    ob_mp_hbridge_type,
    MP_QSTR_HBridge,
    MP_TYPE_FLAG_NONE,
    make_new, hbridge_make_new,
    attr, hbridge_attr,
    locals_dict, &hbridge_locals
    );

/* ---- A DC motor's IO, from Python: the same three calls a serial-bus slot's IO takes. ---- */

static mp_obj_t dc_io_read_angle(mp_obj_t self_in) {
    dc_io_obj_t *self = MP_OBJ_TO_PTR(self_in);
    float angle;
    return self->base.io.read_angle(self->base.io.ctx, &angle) ? mp_obj_new_float(angle) : mp_const_none;
}
static MP_DEFINE_CONST_FUN_OBJ_1(dc_io_read_angle_obj, dc_io_read_angle);

static mp_obj_t dc_io_write_duty(mp_obj_t self_in, mp_obj_t duty_in) {
    dc_io_obj_t *self = MP_OBJ_TO_PTR(self_in);
    self->base.io.write_duty(self->base.io.ctx, ob_mp_float(duty_in, "write_duty", "duty_pct"));
    return mp_const_none;
}
static MP_DEFINE_CONST_FUN_OBJ_2(dc_io_write_duty_obj, dc_io_write_duty);

static mp_obj_t dc_io_coast(mp_obj_t self_in) {
    dc_io_obj_t *self = MP_OBJ_TO_PTR(self_in);
    self->base.io.write_coast(self->base.io.ctx);
    return mp_const_none;
}
static MP_DEFINE_CONST_FUN_OBJ_1(dc_io_coast_obj, dc_io_coast);

static const mp_rom_map_elem_t dc_io_locals_table[] = {
    {MP_ROM_QSTR(MP_QSTR_read_angle), MP_ROM_PTR(&dc_io_read_angle_obj)},
    {MP_ROM_QSTR(MP_QSTR_write_duty), MP_ROM_PTR(&dc_io_write_duty_obj)},
    {MP_ROM_QSTR(MP_QSTR_coast), MP_ROM_PTR(&dc_io_coast_obj)},
};
static MP_DEFINE_CONST_DICT(dc_io_locals, dc_io_locals_table);

static void dc_io_attr(mp_obj_t self_in, qstr attr, mp_obj_t *dest) {
    ob_mp_locked_attr(self_in, attr, dest, &dc_io_locals);
}

static MP_DEFINE_CONST_OBJ_TYPE(
    dc_io_type,
    MP_QSTR_HBridgeMotorIO,
    MP_TYPE_FLAG_NONE,
    attr, dc_io_attr,
    locals_dict, &dc_io_locals,
    parent, &ob_mp_motor_io_type
    );
