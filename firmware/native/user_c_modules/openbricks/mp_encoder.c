/*
 * PCNTEncoder: the encoder core (encoder.h) in MicroPython (host: py_encoder.c).
 *
 * On the hub, PCNTEncoder(counts_per_rev, pin_a=, pin_b=, unit=, filter=)
 * counts the pins on a PCNT unit (mp_pcnt_esp32.c) and the hard tick reads
 * the unit every millisecond, so the 16-bit counter is unwrapped whatever
 * Python is doing. counter= takes any native counter instead (the unix
 * port's tests: an emulated PCNT unit in C, read by the hard tick the same
 * way). Without either, readings come through sample(raw), as in the host
 * tests.
 */
#include "encoder.h"
#include "mp_bindings.h"

typedef struct {
    mp_obj_base_t base;
    ob_encoder_t enc;
    bool closed;
    bool hardware; /* counting a PCNT unit or a native counter, polled by the hard tick */
    mp_obj_t counter; /* the native counter object read (kept alive), or MP_OBJ_NULL */
} pcnt_encoder_obj_t;

static void poll(void *ctx) {
    ob_encoder_poll(ctx);
}

static mp_obj_t pcnt_encoder_make_new(const mp_obj_type_t *type, size_t n_args, size_t n_kw,
                                      const mp_obj_t *all_args) {
    enum { ARG_counts_per_rev, ARG_invert, ARG_modulus, ARG_pin_a, ARG_pin_b, ARG_unit, ARG_filter, ARG_counter };
    static const mp_arg_t allowed[] = {
        {MP_QSTR_counts_per_rev, MP_ARG_REQUIRED | MP_ARG_OBJ, {.u_obj = MP_OBJ_NULL}},
        {MP_QSTR_invert, MP_ARG_KW_ONLY | MP_ARG_BOOL, {.u_bool = false}},
        {MP_QSTR_modulus, MP_ARG_KW_ONLY | MP_ARG_OBJ, {.u_obj = MP_OBJ_NULL}},
        {MP_QSTR_pin_a, MP_ARG_KW_ONLY | MP_ARG_OBJ, {.u_obj = mp_const_none}},
        {MP_QSTR_pin_b, MP_ARG_KW_ONLY | MP_ARG_OBJ, {.u_obj = mp_const_none}},
        {MP_QSTR_unit, MP_ARG_KW_ONLY | MP_ARG_INT, {.u_int = 0}},
        {MP_QSTR_filter, MP_ARG_KW_ONLY | MP_ARG_INT, {.u_int = OB_PCNT_FILTER_MAX_CYCLES}},
        {MP_QSTR_counter, MP_ARG_KW_ONLY | MP_ARG_OBJ, {.u_obj = mp_const_none}},
    };
    mp_arg_val_t args[MP_ARRAY_SIZE(allowed)];
    mp_arg_parse_all_kw_array(n_args, n_kw, all_args, MP_ARRAY_SIZE(allowed), allowed, args);
    bool pins = args[ARG_pin_a].u_obj != mp_const_none || args[ARG_pin_b].u_obj != mp_const_none;
    #if !defined(ESP_PLATFORM)
    if (pins) {
        mp_raise_msg(&mp_type_OSError, MP_ERROR_TEXT("PCNTEncoder: this build has no PCNT peripheral (only the ESP32 "
                                                     "firmware counts pins); feed the counter's readings with "
                                                     "sample(raw)"));
    }
    #endif
    ob_encoder_config_t cfg;
    ob_encoder_default_config(&cfg, ob_mp_int32(args[ARG_counts_per_rev].u_obj, "PCNTEncoder()", "counts_per_rev"));
    cfg.invert = args[ARG_invert].u_bool;
    if (args[ARG_modulus].u_obj != MP_OBJ_NULL) {
        cfg.modulus = ob_mp_int32(args[ARG_modulus].u_obj, "PCNTEncoder()", "modulus");
    }
    /* A finaliser: a soft reset sweeps the heap, and the hard tick must stop reading it first. */
    pcnt_encoder_obj_t *self = mp_obj_malloc_with_finaliser(pcnt_encoder_obj_t, type);
    ob_encoder_error_t error = ob_encoder_init(&self->enc, &cfg, NULL);
    if (error != OB_ENCODER_OK) {
        mp_raise_msg_varg(&mp_type_ValueError, MP_ERROR_TEXT("PCNTEncoder(): %s"), ob_encoder_strerror(error));
    }
    self->closed = false;
    self->hardware = false;
    self->counter = MP_OBJ_NULL;
    if (args[ARG_counter].u_obj != mp_const_none) {
        const ob_pcnt_t *link = ob_mp_native_counter_get(args[ARG_counter].u_obj);
        if (link == NULL || pins) {
            mp_raise_TypeError(MP_ERROR_TEXT("PCNTEncoder(): counter= takes a native counter (not with pin_a/pin_b)"));
        }
        self->counter = args[ARG_counter].u_obj;
        ob_encoder_init(&self->enc, &cfg, link);
        ob_encoder_poll(&self->enc); /* where counting starts */
        self->hardware = true;
        ob_mp_hard_tick_poll(MP_OBJ_FROM_PTR(self), poll, &self->enc);
    }
    #if defined(ESP_PLATFORM)
    if (pins) {
        if (args[ARG_pin_a].u_obj == mp_const_none || args[ARG_pin_b].u_obj == mp_const_none) {
            mp_raise_ValueError(MP_ERROR_TEXT("PCNTEncoder: give both encoder channels, pin_a= and pin_b="));
        }
        mp_int_t filter = args[ARG_filter].u_int;
        if (filter < 0 || filter > OB_PCNT_FILTER_MAX_CYCLES) {
            mp_raise_msg_varg(&mp_type_ValueError,
                              MP_ERROR_TEXT("pcnt_filter=%d: the PCNT glitch filter takes 0..1023 APB cycles"),
                              (int)filter);
        }
        if (args[ARG_modulus].u_obj != MP_OBJ_NULL && cfg.modulus != OB_PCNT_LIMIT) {
            mp_raise_ValueError(MP_ERROR_TEXT("PCNTEncoder: a PCNT unit's counter repeats every 32767 counts; "
                                              "leave modulus out"));
        }
        ob_pcnt_t pcnt;
        ob_mp_pcnt_esp32_open(mp_obj_get_int(args[ARG_pin_a].u_obj), mp_obj_get_int(args[ARG_pin_b].u_obj),
                              (int)filter, &pcnt);
        ob_encoder_init(&self->enc, &cfg, &pcnt);
        ob_encoder_poll(&self->enc); /* where counting starts */
        self->hardware = true;
        ob_mp_hard_tick_poll(MP_OBJ_FROM_PTR(self), poll, &self->enc);
    }
    #endif
    (void)args[ARG_unit].u_int; /* the runtime's bookkeeping of units; the driver picks the hardware unit */
    return MP_OBJ_FROM_PTR(self);
}

static pcnt_encoder_obj_t *open_self(mp_obj_t self_in, const char *method) {
    pcnt_encoder_obj_t *self = MP_OBJ_TO_PTR(self_in);
    if (self->closed) {
        mp_raise_msg_varg(&mp_type_ValueError,
                          MP_ERROR_TEXT("PCNTEncoder.%s(): the encoder was closed; construct a new one"), method);
    }
    return self;
}

/* The hub's reading is at most a tick old; read the unit now so a caller sees the latest edge. */
static void refresh(pcnt_encoder_obj_t *self) {
    if (self->hardware) {
        ob_encoder_poll(&self->enc);
    }
}

static mp_obj_t pcnt_encoder_sample(mp_obj_t self_in, mp_obj_t raw_in) {
    pcnt_encoder_obj_t *self = open_self(self_in, "sample");
    ob_encoder_sample(&self->enc, ob_mp_int32(raw_in, "PCNTEncoder.sample()", "raw"));
    return mp_const_none;
}
static MP_DEFINE_CONST_FUN_OBJ_2(pcnt_encoder_sample_obj, pcnt_encoder_sample);

static mp_obj_t pcnt_encoder_count(mp_obj_t self_in) {
    pcnt_encoder_obj_t *self = open_self(self_in, "count");
    refresh(self);
    return mp_obj_new_int_from_ll((long long)ob_encoder_count(&self->enc));
}
static MP_DEFINE_CONST_FUN_OBJ_1(pcnt_encoder_count_obj, pcnt_encoder_count);

static mp_obj_t pcnt_encoder_reset(size_t n_args, const mp_obj_t *args) {
    pcnt_encoder_obj_t *self = open_self(args[0], "reset");
    refresh(self);
    ob_encoder_reset_count(&self->enc, n_args > 1 ? (int64_t)mp_obj_get_int(args[1]) : 0);
    return mp_const_none;
}
static MP_DEFINE_CONST_FUN_OBJ_VAR_BETWEEN(pcnt_encoder_reset_obj, 1, 2, pcnt_encoder_reset);

static mp_obj_t pcnt_encoder_angle(mp_obj_t self_in) {
    pcnt_encoder_obj_t *self = open_self(self_in, "angle");
    refresh(self);
    return mp_obj_new_float(ob_encoder_angle_deg(&self->enc));
}
static MP_DEFINE_CONST_FUN_OBJ_1(pcnt_encoder_angle_obj, pcnt_encoder_angle);

static mp_obj_t pcnt_encoder_direction(mp_obj_t self_in) {
    pcnt_encoder_obj_t *self = MP_OBJ_TO_PTR(self_in);
    return MP_OBJ_NEW_SMALL_INT(ob_encoder_direction(&self->enc));
}
static MP_DEFINE_CONST_FUN_OBJ_1(pcnt_encoder_direction_obj, pcnt_encoder_direction);

static mp_obj_t pcnt_encoder_max_step(mp_obj_t self_in) {
    pcnt_encoder_obj_t *self = MP_OBJ_TO_PTR(self_in);
    return mp_obj_new_int(ob_encoder_max_step(&self->enc));
}
static MP_DEFINE_CONST_FUN_OBJ_1(pcnt_encoder_max_step_obj, pcnt_encoder_max_step);

static mp_obj_t pcnt_encoder_close(mp_obj_t self_in) {
    pcnt_encoder_obj_t *self = MP_OBJ_TO_PTR(self_in);
    if (self->hardware) {
        ob_mp_hard_tick_unpoll(&self->enc);
        #if defined(ESP_PLATFORM)
        if (self->counter == MP_OBJ_NULL) {
            ob_mp_pcnt_esp32_close(&self->enc.pcnt);
        }
        #endif
        self->counter = MP_OBJ_NULL;
        self->hardware = false;
        /* An H-bridge's motor IO may still hold this core: it must find no counter to read, not a freed unit. */
        self->enc.pcnt = (ob_pcnt_t){NULL, NULL};
    }
    self->closed = true;
    return mp_const_none;
}
static MP_DEFINE_CONST_FUN_OBJ_1(pcnt_encoder_close_obj, pcnt_encoder_close);

static const mp_rom_map_elem_t pcnt_encoder_locals_table[] = {
    {MP_ROM_QSTR(MP_QSTR_sample), MP_ROM_PTR(&pcnt_encoder_sample_obj)},
    {MP_ROM_QSTR(MP_QSTR_count), MP_ROM_PTR(&pcnt_encoder_count_obj)},
    {MP_ROM_QSTR(MP_QSTR_reset), MP_ROM_PTR(&pcnt_encoder_reset_obj)},
    {MP_ROM_QSTR(MP_QSTR_angle), MP_ROM_PTR(&pcnt_encoder_angle_obj)},
    {MP_ROM_QSTR(MP_QSTR_direction), MP_ROM_PTR(&pcnt_encoder_direction_obj)},
    {MP_ROM_QSTR(MP_QSTR_max_step), MP_ROM_PTR(&pcnt_encoder_max_step_obj)},
    {MP_ROM_QSTR(MP_QSTR_close), MP_ROM_PTR(&pcnt_encoder_close_obj)},
    {MP_ROM_QSTR(MP_QSTR___del__), MP_ROM_PTR(&pcnt_encoder_close_obj)},
    #if defined(ESP_PLATFORM)
    {MP_ROM_QSTR(MP_QSTR_HARDWARE), MP_ROM_TRUE},
    #else
    {MP_ROM_QSTR(MP_QSTR_HARDWARE), MP_ROM_FALSE},
    #endif
};
static MP_DEFINE_CONST_DICT(pcnt_encoder_locals, pcnt_encoder_locals_table);

/* Methods run under the motor lock: the hard tick samples the same encoder from its own context. */
static void pcnt_encoder_attr(mp_obj_t self_in, qstr attr, mp_obj_t *dest) {
    ob_mp_locked_attr(self_in, attr, dest, &pcnt_encoder_locals);
}

ob_encoder_t *ob_mp_pcnt_encoder_get(mp_obj_t obj) {
    if (!mp_obj_is_type(obj, &ob_mp_pcnt_encoder_type)) {
        return NULL;
    }
    pcnt_encoder_obj_t *self = MP_OBJ_TO_PTR(obj);
    return self->closed ? NULL : &self->enc;
}

MP_DEFINE_CONST_OBJ_TYPE(
    ob_mp_pcnt_encoder_type,
    MP_QSTR_PCNTEncoder,
    MP_TYPE_FLAG_NONE,
    make_new, pcnt_encoder_make_new,
    attr, pcnt_encoder_attr,
    locals_dict, &pcnt_encoder_locals
    );
