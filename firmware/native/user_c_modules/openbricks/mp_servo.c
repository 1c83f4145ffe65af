/*
 * Servo: closed-loop control of one motor (host: py_servo.c).
 *
 * With read_angle/write_duty/write_coast callables (the encoder motors'
 * drivers) it is a native motor_process subscriber and only the IO crosses
 * into Python; with none, update(now_ms, measured_deg) runs one step with no
 * Python call. An exception raised by a callable cannot cross the core's C
 * frames: it is kept and raised when the core returns, and a read that raised
 * counts as a failed read, so the core's silent-feedback halt protects the
 * motor whatever the caller does with the exception.
 */
#include <string.h>

#include "mp_bindings.h"
#include "servo.h"
#include "servo_settings.h"

typedef struct {
    ob_mp_subscriber_t sub;
    ob_servo_t servo;
    mp_obj_t read_angle; /* MP_OBJ_NULL on the direct (update) path */
    mp_obj_t write_duty;
    mp_obj_t write_coast;
} servo_obj_t;

/* ---- IO adapters. ---- */

static bool io_read_angle(void *ctx, float *angle_deg) {
    servo_obj_t *self = ctx;
    nlr_buf_t nlr;
    if (nlr_push(&nlr) == 0) {
        mp_obj_t result = mp_call_function_0(self->read_angle);
        bool fresh = result != mp_const_none;
        if (fresh) {
            *angle_deg = ob_mp_float(result, "Servo", "the value returned by read_angle");
        }
        nlr_pop();
        return fresh;
    }
    ob_mp_subscriber_stash(&self->sub, MP_OBJ_FROM_PTR(nlr.ret_val));
    return false;
}

static void io_write_duty(void *ctx, float duty_pct) {
    servo_obj_t *self = ctx;
    nlr_buf_t nlr;
    if (nlr_push(&nlr) == 0) {
        mp_call_function_1(self->write_duty, mp_obj_new_float(duty_pct));
        nlr_pop();
    } else {
        ob_mp_subscriber_stash(&self->sub, MP_OBJ_FROM_PTR(nlr.ret_val));
    }
}

static void io_write_coast(void *ctx) {
    servo_obj_t *self = ctx;
    nlr_buf_t nlr;
    if (nlr_push(&nlr) == 0) {
        mp_call_function_0(self->write_coast);
        nlr_pop();
    } else {
        ob_mp_subscriber_stash(&self->sub, MP_OBJ_FROM_PTR(nlr.ret_val));
    }
}

static void servo_tick_fn(void *ctx, uint32_t now_ms) {
    servo_obj_t *self = ctx;
    ob_servo_tick(&self->servo, now_ms); /* callable errors stay in sub.error for motor_process */
}

/* ---- Settings: the core's table (servo_settings.h) checks them; this only parses. ---- */

static void set_one(ob_servo_config_t *cfg, qstr name, mp_obj_t value, const char *where) {
    char msg[OB_SERVO_SETTING_MSG_SIZE];
    const ob_servo_setting_t *setting = ob_servo_setting_find(qstr_str(name), where, msg, sizeof(msg));
    if (setting == NULL) {
        mp_raise_msg_varg(&mp_type_TypeError, MP_ERROR_TEXT("%s"), msg);
    }
    bool is_int = mp_obj_is_int(value) && value != mp_const_true && value != mp_const_false;
    double number = 0.0;
    if (is_int) {
        ob_mp_float(value, where, setting->name); /* in range of a float */
        number = (double)mp_obj_get_float(value);
    } else if (!setting->is_ms) {
        number = (double)ob_mp_float(value, where, setting->name);
    }
    ob_setting_status_t status =
        ob_servo_setting_set(cfg, setting, number, is_int, mp_obj_get_type_str(value), where, msg, sizeof(msg));
    if (status != OB_SETTING_OK) {
        mp_raise_msg_varg(status == OB_SETTING_TYPE_ERROR ? &mp_type_TypeError : &mp_type_ValueError,
                          MP_ERROR_TEXT("%s"), msg);
    }
}

/* Keyword settings onto cfg; names in `skip` are the constructor's own arguments. */
static void apply_settings(ob_servo_config_t *cfg, mp_map_t *kw_args, const char *where, const qstr *skip,
                           size_t n_skip) {
    for (size_t i = 0; i < kw_args->alloc; i++) {
        if (!mp_map_slot_is_filled(kw_args, i)) {
            continue;
        }
        qstr name = mp_obj_str_get_qstr(kw_args->table[i].key);
        bool skipped = false;
        for (size_t k = 0; k < n_skip; k++) {
            skipped = skipped || skip[k] == name;
        }
        if (!skipped) {
            set_one(cfg, name, kw_args->table[i].value, where);
        }
    }
}

static mp_obj_t settings_dict(const ob_servo_config_t *cfg) {
    mp_obj_t dict = mp_obj_new_dict(OB_SERVO_SETTINGS_COUNT);
    for (size_t i = 0; i < OB_SERVO_SETTINGS_COUNT; i++) {
        const ob_servo_setting_t *setting = &ob_servo_settings[i];
        double number = ob_servo_setting_get(cfg, setting);
        mp_obj_t value = setting->is_ms ? mp_obj_new_int_from_uint((mp_uint_t)number) : mp_obj_new_float(number);
        mp_obj_dict_store(dict, mp_obj_new_str(setting->name, strlen(setting->name)), value);
    }
    return dict;
}

/* ---- Construction. ---- */

static mp_obj_t lookup_kw(mp_map_t *kw_args, qstr name) {
    mp_map_elem_t *elem = mp_map_lookup(kw_args, MP_OBJ_NEW_QSTR(name), MP_MAP_LOOKUP);
    if (elem == NULL || elem->value == mp_const_none) {
        return MP_OBJ_NULL;
    }
    return elem->value;
}

static void require_callable(mp_obj_t obj, const char *name) {
    if (obj != MP_OBJ_NULL && !mp_obj_is_callable(obj)) {
        mp_raise_msg_varg(&mp_type_TypeError, MP_ERROR_TEXT("Servo: %s must be callable, not %s"), name,
                          mp_obj_get_type_str(obj));
    }
}

static mp_obj_t servo_make_new(const mp_obj_type_t *type, size_t n_args, size_t n_kw, const mp_obj_t *args) {
    static const qstr own_args[] = {MP_QSTR_read_angle, MP_QSTR_write_duty, MP_QSTR_write_coast, MP_QSTR_duty_limit,
                                    MP_QSTR_io};
    if (n_args != 0) {
        mp_raise_TypeError(
            MP_ERROR_TEXT("Servo() takes keyword arguments only: read_angle=, write_duty=, write_coast= and settings"));
    }
    mp_map_t kw_args;
    mp_map_init_fixed_table(&kw_args, n_kw, args);
    mp_obj_t read = lookup_kw(&kw_args, MP_QSTR_read_angle);
    mp_obj_t write = lookup_kw(&kw_args, MP_QSTR_write_duty);
    mp_obj_t coast = lookup_kw(&kw_args, MP_QSTR_write_coast);
    mp_obj_t duty_limit = lookup_kw(&kw_args, MP_QSTR_duty_limit);
    mp_obj_t native_io = lookup_kw(&kw_args, MP_QSTR_io);
    ob_motor_io_t native_motor_io;
    if (native_io != MP_OBJ_NULL && !ob_mp_motor_io_get(native_io, &native_motor_io)) {
        mp_raise_msg_varg(&mp_type_TypeError,
                          MP_ERROR_TEXT("Servo: io= must be a native MotorIO (a bus engine's motor_io(slot)), not %s"),
                          mp_obj_get_type_str(native_io));
    }
    require_callable(read, "read_angle");
    require_callable(write, "write_duty");
    require_callable(coast, "write_coast");
    int given = (read != MP_OBJ_NULL) + (write != MP_OBJ_NULL) + (coast != MP_OBJ_NULL);
    if (native_io != MP_OBJ_NULL && given != 0) {
        mp_raise_TypeError(MP_ERROR_TEXT("Servo: give io= or read_angle=, write_duty= and write_coast=, not both"));
    }
    if (given != 0 && given != 3) {
        mp_raise_TypeError(MP_ERROR_TEXT("Servo: give all of read_angle, write_duty and write_coast (a motor that "
                                         "is ticked by motor_process), or none of them (drive it with update())"));
    }
    ob_servo_config_t cfg;
    ob_servo_config_default(&cfg);
    apply_settings(&cfg, &kw_args, "Servo", own_args, MP_ARRAY_SIZE(own_args));
    float limit = 100.0f;
    if (duty_limit != MP_OBJ_NULL) {
        limit = ob_mp_float(duty_limit, "Servo", "duty_limit");
        char msg[OB_SERVO_SETTING_MSG_SIZE];
        if (!ob_servo_duty_limit_valid(limit, "Servo", "duty_limit", "", msg, sizeof(msg))) {
            mp_raise_msg_varg(&mp_type_ValueError, MP_ERROR_TEXT("%s"), msg);
        }
    }
    cfg.duty_limit_pct = limit;

    servo_obj_t *self = mp_obj_malloc(servo_obj_t, type);
    self->sub.error = MP_OBJ_NULL;
    self->read_angle = read;
    self->write_duty = write;
    self->write_coast = coast;
    ob_motor_io_t io;
    self->sub.hard_safe = false;
    if (native_io != MP_OBJ_NULL) {
        io = native_motor_io;
        self->read_angle = native_io; /* keeps the provider alive; never called */
        self->sub.tick_fn = servo_tick_fn;
        self->sub.tick_ctx = self;
        self->sub.hard_safe = true; /* no Python per tick: the hard tick may run it */
    } else {
        bool ticked = given == 3; /* by motor_process; else stepped with update() */
        io = ticked ? (ob_motor_io_t){io_read_angle, io_write_duty, io_write_coast, self} : ob_servo_direct_io;
        self->sub.tick_fn = ticked ? servo_tick_fn : NULL;
        self->sub.tick_ctx = ticked ? self : NULL;
    }
    ob_servo_init(&self->servo, &io, &cfg);
    return MP_OBJ_FROM_PTR(self);
}

/* ---- Commands. Each may write to the motor at once (dc, brake, coast, a halt). ---- */

static mp_obj_t done_or_raise(servo_obj_t *self) {
    ob_mp_subscriber_raise(&self->sub);
    return mp_const_none;
}

static mp_obj_t servo_run_speed(mp_obj_t self_in, mp_obj_t speed_in) {
    servo_obj_t *self = MP_OBJ_TO_PTR(self_in);
    ob_servo_run_speed(&self->servo, ob_mp_float(speed_in, "Servo.run_speed", "speed_dps"));
    return done_or_raise(self);
}
static MP_DEFINE_CONST_FUN_OBJ_2(servo_run_speed_obj, servo_run_speed);

/* run_target and run_angle share their arguments. */
static mp_obj_t servo_move(size_t n_args, const mp_obj_t *pos_args, mp_map_t *kw_args, bool relative) {
    enum { ARG_self, ARG_speed_dps, ARG_value, ARG_then, ARG_accel_dps2, ARG_decel_dps2 };
    const mp_arg_t allowed[] = {
        {MP_QSTR_self, MP_ARG_REQUIRED | MP_ARG_OBJ, {.u_obj = MP_OBJ_NULL}},
        {MP_QSTR_speed_dps, MP_ARG_REQUIRED | MP_ARG_OBJ, {.u_obj = MP_OBJ_NULL}},
        {relative ? MP_QSTR_angle_deg : MP_QSTR_target_deg, MP_ARG_REQUIRED | MP_ARG_OBJ, {.u_obj = MP_OBJ_NULL}},
        {MP_QSTR_then, MP_ARG_OBJ, {.u_obj = MP_OBJ_NULL}},
        {MP_QSTR_accel_dps2, MP_ARG_OBJ, {.u_obj = mp_const_none}},
        {MP_QSTR_decel_dps2, MP_ARG_OBJ, {.u_obj = mp_const_none}},
    };
    mp_arg_val_t args[MP_ARRAY_SIZE(allowed)];
    mp_arg_parse_all(n_args, pos_args, kw_args, MP_ARRAY_SIZE(allowed), allowed, args);
    servo_obj_t *self = MP_OBJ_TO_PTR(args[ARG_self].u_obj);
    const char *where = relative ? "Servo.run_angle" : "Servo.run_target";
    float speed = ob_mp_float(args[ARG_speed_dps].u_obj, where, "speed_dps");
    float value = ob_mp_float(args[ARG_value].u_obj, where, relative ? "angle_deg" : "target_deg");
    ob_then_t then = args[ARG_then].u_obj != MP_OBJ_NULL ? ob_mp_then(args[ARG_then].u_obj, where) : OB_THEN_HOLD;
    float accel = self->servo.cfg.accel_dps2, decel = self->servo.cfg.decel_dps2;
    if (ob_mp_given(args[ARG_accel_dps2].u_obj)) {
        accel = ob_mp_positive_float(args[ARG_accel_dps2].u_obj, where, "accel_dps2");
        decel = accel; /* one rate given: use it both ways, like the manual's accel_dps2 */
    }
    if (ob_mp_given(args[ARG_decel_dps2].u_obj)) {
        decel = ob_mp_positive_float(args[ARG_decel_dps2].u_obj, where, "decel_dps2");
    }
    if (speed == 0.0f) {
        mp_raise_msg_varg(&mp_type_ValueError, MP_ERROR_TEXT("%s: speed_dps must not be 0 (use hold() to stay in place)"),
                          where);
    }
    ob_servo_move(&self->servo, speed, value, relative, then, accel, decel);
    return done_or_raise(self);
}

static mp_obj_t servo_run_target(size_t n_args, const mp_obj_t *pos_args, mp_map_t *kw_args) {
    return servo_move(n_args, pos_args, kw_args, false);
}
static MP_DEFINE_CONST_FUN_OBJ_KW(servo_run_target_obj, 1, servo_run_target);

static mp_obj_t servo_run_angle(size_t n_args, const mp_obj_t *pos_args, mp_map_t *kw_args) {
    return servo_move(n_args, pos_args, kw_args, true);
}
static MP_DEFINE_CONST_FUN_OBJ_KW(servo_run_angle_obj, 1, servo_run_angle);

static mp_obj_t servo_hold(mp_obj_t self_in) {
    servo_obj_t *self = MP_OBJ_TO_PTR(self_in);
    ob_servo_hold(&self->servo);
    return done_or_raise(self);
}
static MP_DEFINE_CONST_FUN_OBJ_1(servo_hold_obj, servo_hold);

static mp_obj_t servo_dc(mp_obj_t self_in, mp_obj_t duty_in) {
    servo_obj_t *self = MP_OBJ_TO_PTR(self_in);
    float duty = ob_mp_float(duty_in, "Servo.dc", "duty_pct");
    if (duty < -100.0f || duty > 100.0f) {
        mp_raise_msg_varg(&mp_type_ValueError, MP_ERROR_TEXT("Servo.dc: duty_pct must be within -100..100, got %g"),
                          (double)duty);
    }
    ob_servo_dc(&self->servo, duty);
    return done_or_raise(self);
}
static MP_DEFINE_CONST_FUN_OBJ_2(servo_dc_obj, servo_dc);

static mp_obj_t servo_brake(mp_obj_t self_in) {
    servo_obj_t *self = MP_OBJ_TO_PTR(self_in);
    ob_servo_brake(&self->servo);
    return done_or_raise(self);
}
static MP_DEFINE_CONST_FUN_OBJ_1(servo_brake_obj, servo_brake);

static mp_obj_t servo_coast(mp_obj_t self_in) {
    servo_obj_t *self = MP_OBJ_TO_PTR(self_in);
    ob_servo_coast(&self->servo);
    return done_or_raise(self);
}
static MP_DEFINE_CONST_FUN_OBJ_1(servo_coast_obj, servo_coast);

static mp_obj_t servo_stop(size_t n_args, const mp_obj_t *pos_args, mp_map_t *kw_args) {
    enum { ARG_self, ARG_then };
    static const mp_arg_t allowed[] = {
        {MP_QSTR_self, MP_ARG_REQUIRED | MP_ARG_OBJ, {.u_obj = MP_OBJ_NULL}},
        {MP_QSTR_then, MP_ARG_OBJ, {.u_obj = MP_OBJ_NULL}},
    };
    mp_arg_val_t args[MP_ARRAY_SIZE(allowed)];
    mp_arg_parse_all(n_args, pos_args, kw_args, MP_ARRAY_SIZE(allowed), allowed, args);
    servo_obj_t *self = MP_OBJ_TO_PTR(args[ARG_self].u_obj);
    ob_then_t then = args[ARG_then].u_obj != MP_OBJ_NULL ? ob_mp_then(args[ARG_then].u_obj, "Servo.stop") : OB_THEN_COAST;
    ob_servo_stop(&self->servo, then);
    return done_or_raise(self);
}
static MP_DEFINE_CONST_FUN_OBJ_KW(servo_stop_obj, 1, servo_stop);

static mp_obj_t servo_reset_angle(size_t n_args, const mp_obj_t *pos_args, mp_map_t *kw_args) {
    enum { ARG_self, ARG_angle_deg };
    static const mp_arg_t allowed[] = {
        {MP_QSTR_self, MP_ARG_REQUIRED | MP_ARG_OBJ, {.u_obj = MP_OBJ_NULL}},
        {MP_QSTR_angle_deg, MP_ARG_OBJ, {.u_obj = MP_OBJ_NULL}},
    };
    mp_arg_val_t args[MP_ARRAY_SIZE(allowed)];
    mp_arg_parse_all(n_args, pos_args, kw_args, MP_ARRAY_SIZE(allowed), allowed, args);
    servo_obj_t *self = MP_OBJ_TO_PTR(args[ARG_self].u_obj);
    float angle = 0.0f;
    if (args[ARG_angle_deg].u_obj != MP_OBJ_NULL) {
        angle = ob_mp_float(args[ARG_angle_deg].u_obj, "Servo.reset_angle", "angle_deg");
    }
    ob_servo_reset_angle(&self->servo, angle);
    return mp_const_none;
}
static MP_DEFINE_CONST_FUN_OBJ_KW(servo_reset_angle_obj, 1, servo_reset_angle);

static mp_obj_t servo_set_duty_limit(mp_obj_t self_in, mp_obj_t limit_in) {
    servo_obj_t *self = MP_OBJ_TO_PTR(self_in);
    float limit = 100.0f;
    if (limit_in != mp_const_none) {
        limit = ob_mp_float(limit_in, "Servo.set_duty_limit", "limit_pct");
        char msg[OB_SERVO_SETTING_MSG_SIZE];
        if (!ob_servo_duty_limit_valid(limit, "Servo.set_duty_limit", "limit_pct", " (None lifts it)", msg,
                                       sizeof(msg))) {
            mp_raise_msg_varg(&mp_type_ValueError, MP_ERROR_TEXT("%s"), msg);
        }
    }
    ob_servo_set_duty_limit(&self->servo, limit);
    return mp_const_none;
}
static MP_DEFINE_CONST_FUN_OBJ_2(servo_set_duty_limit_obj, servo_set_duty_limit);

/* ---- Ticking. ---- */

static mp_obj_t duty_result(const ob_servo_t *s) {
    float duty;
    return ob_servo_duty_out(s, &duty) ? mp_obj_new_float(duty) : mp_const_none;
}

static mp_obj_t servo_tick(mp_obj_t self_in, mp_obj_t now_in) {
    servo_obj_t *self = MP_OBJ_TO_PTR(self_in);
    uint32_t now_ms = ob_mp_time_ms(now_in, "Servo.tick");
    if (self->read_angle == MP_OBJ_NULL) {
        mp_raise_TypeError(MP_ERROR_TEXT("Servo.tick: this Servo has no read_angle/write_duty/write_coast callables; "
                                         "use update(now_ms, measured_deg)"));
    }
    ob_servo_tick(&self->servo, now_ms);
    return done_or_raise(self);
}
static MP_DEFINE_CONST_FUN_OBJ_2(servo_tick_obj, servo_tick);

static mp_obj_t servo_update(mp_obj_t self_in, mp_obj_t now_in, mp_obj_t measured_in) {
    servo_obj_t *self = MP_OBJ_TO_PTR(self_in);
    static const char *where = "Servo.update";
    uint32_t now_ms = ob_mp_time_ms(now_in, where);
    bool have = measured_in != mp_const_none;
    float measured = have ? ob_mp_float(measured_in, where, "measured_deg") : 0.0f;
    ob_servo_step(&self->servo, now_ms, have, measured);
    ob_mp_subscriber_raise(&self->sub);
    return duty_result(&self->servo);
}
static MP_DEFINE_CONST_FUN_OBJ_3(servo_update_obj, servo_update);

/* ---- Queries. ---- */

static mp_obj_t servo_angle(mp_obj_t self_in) {
    servo_obj_t *self = MP_OBJ_TO_PTR(self_in);
    return mp_obj_new_float(ob_servo_angle_deg(&self->servo));
}
static MP_DEFINE_CONST_FUN_OBJ_1(servo_angle_obj, servo_angle);

static mp_obj_t servo_speed(mp_obj_t self_in) {
    servo_obj_t *self = MP_OBJ_TO_PTR(self_in);
    return mp_obj_new_float(ob_servo_speed_dps(&self->servo));
}
static MP_DEFINE_CONST_FUN_OBJ_1(servo_speed_obj, servo_speed);

static mp_obj_t servo_done(mp_obj_t self_in) {
    servo_obj_t *self = MP_OBJ_TO_PTR(self_in);
    return mp_obj_new_bool(ob_servo_is_done(&self->servo));
}
static MP_DEFINE_CONST_FUN_OBJ_1(servo_done_obj, servo_done);

static mp_obj_t servo_stalled(mp_obj_t self_in) {
    servo_obj_t *self = MP_OBJ_TO_PTR(self_in);
    return mp_obj_new_bool(ob_servo_is_stalled(&self->servo));
}
static MP_DEFINE_CONST_FUN_OBJ_1(servo_stalled_obj, servo_stalled);

static mp_obj_t servo_settings(size_t n_args, const mp_obj_t *pos_args, mp_map_t *kw_args) {
    if (n_args != 1) {
        mp_raise_TypeError(MP_ERROR_TEXT("Servo.settings() takes keyword arguments only"));
    }
    servo_obj_t *self = MP_OBJ_TO_PTR(pos_args[0]);
    if (kw_args->used > 0) {
        ob_servo_config_t cfg = self->servo.cfg;
        apply_settings(&cfg, kw_args, "Servo.settings", NULL, 0);
        ob_servo_configure(&self->servo, &cfg);
    }
    return settings_dict(&self->servo.cfg);
}
static MP_DEFINE_CONST_FUN_OBJ_KW(servo_settings_obj, 1, servo_settings);

static void store(mp_obj_t dict, qstr key, mp_obj_t value) {
    mp_obj_dict_store(dict, MP_OBJ_NEW_QSTR(key), value);
}

static mp_obj_t servo_state(mp_obj_t self_in) {
    servo_obj_t *self = MP_OBJ_TO_PTR(self_in);
    const ob_servo_t *s = &self->servo;
    const char *mode = ob_servo_mode_name(s->mode);
    const char *then = ob_mp_then_name(s->then);
    mp_obj_t state = mp_obj_new_dict(15);
    store(state, MP_QSTR_mode, mp_obj_new_str(mode, strlen(mode)));
    store(state, MP_QSTR_then, mp_obj_new_str(then, strlen(then)));
    store(state, MP_QSTR_done, mp_obj_new_bool(s->done));
    store(state, MP_QSTR_stalled, mp_obj_new_bool(s->stalled));
    store(state, MP_QSTR_feedback_lost, mp_obj_new_bool(s->feedback_lost));
    store(state, MP_QSTR_failed_reads, mp_obj_new_int_from_uint(s->failed_reads));
    store(state, MP_QSTR_silent_reads, mp_obj_new_int_from_uint(s->silent_ticks));
    store(state, MP_QSTR_angle_deg, mp_obj_new_float(s->angle_deg));
    store(state, MP_QSTR_speed_dps, mp_obj_new_float(s->observer.v_dps));
    store(state, MP_QSTR_duty_pct, duty_result(s));
    store(state, MP_QSTR_duty_limit_pct, mp_obj_new_float(s->duty_limit_pct));
    store(state, MP_QSTR_ref_x_deg, mp_obj_new_float(s->ref.x_deg + s->ref_offset_deg));
    store(state, MP_QSTR_ref_v_dps, mp_obj_new_float(s->ref.v_dps));
    store(state, MP_QSTR_ref_a_dps2, mp_obj_new_float(s->ref.a_dps2));
    store(state, MP_QSTR_now_ms, mp_obj_new_int_from_uint(s->now_ms));
    return state;
}
static MP_DEFINE_CONST_FUN_OBJ_1(servo_state_obj, servo_state);

static const mp_obj_dict_t servo_locals;

static void servo_attr(mp_obj_t self_in, qstr attr, mp_obj_t *dest) {
    if (dest[0] != MP_OBJ_NULL) {
        return; /* read-only */
    }
    servo_obj_t *self = MP_OBJ_TO_PTR(self_in);
    switch (attr) {
        case MP_QSTR_failed_reads:
            dest[0] = mp_obj_new_int_from_uint(self->servo.failed_reads);
            break;
        case MP_QSTR_feedback_lost:
            dest[0] = mp_obj_new_bool(self->servo.feedback_lost);
            break;
        case MP_QSTR_duty:
            dest[0] = duty_result(&self->servo);
            break;
        case MP_QSTR_duty_limit:
            dest[0] = mp_obj_new_float(self->servo.duty_limit_pct);
            break;
        default:
            ob_mp_locked_attr(self_in, attr, dest, &servo_locals); /* methods: under the motor lock */
            break;
    }
}

static const mp_rom_map_elem_t servo_locals_table[] = {
    {MP_ROM_QSTR(MP_QSTR_run_speed), MP_ROM_PTR(&servo_run_speed_obj)},
    {MP_ROM_QSTR(MP_QSTR_run_target), MP_ROM_PTR(&servo_run_target_obj)},
    {MP_ROM_QSTR(MP_QSTR_run_angle), MP_ROM_PTR(&servo_run_angle_obj)},
    {MP_ROM_QSTR(MP_QSTR_hold), MP_ROM_PTR(&servo_hold_obj)},
    {MP_ROM_QSTR(MP_QSTR_dc), MP_ROM_PTR(&servo_dc_obj)},
    {MP_ROM_QSTR(MP_QSTR_brake), MP_ROM_PTR(&servo_brake_obj)},
    {MP_ROM_QSTR(MP_QSTR_coast), MP_ROM_PTR(&servo_coast_obj)},
    {MP_ROM_QSTR(MP_QSTR_stop), MP_ROM_PTR(&servo_stop_obj)},
    {MP_ROM_QSTR(MP_QSTR_reset_angle), MP_ROM_PTR(&servo_reset_angle_obj)},
    {MP_ROM_QSTR(MP_QSTR_set_duty_limit), MP_ROM_PTR(&servo_set_duty_limit_obj)},
    {MP_ROM_QSTR(MP_QSTR_tick), MP_ROM_PTR(&servo_tick_obj)},
    {MP_ROM_QSTR(MP_QSTR_update), MP_ROM_PTR(&servo_update_obj)},
    {MP_ROM_QSTR(MP_QSTR_angle), MP_ROM_PTR(&servo_angle_obj)},
    {MP_ROM_QSTR(MP_QSTR_speed), MP_ROM_PTR(&servo_speed_obj)},
    {MP_ROM_QSTR(MP_QSTR_done), MP_ROM_PTR(&servo_done_obj)},
    {MP_ROM_QSTR(MP_QSTR_is_done), MP_ROM_PTR(&servo_done_obj)},
    {MP_ROM_QSTR(MP_QSTR_stalled), MP_ROM_PTR(&servo_stalled_obj)},
    {MP_ROM_QSTR(MP_QSTR_settings), MP_ROM_PTR(&servo_settings_obj)},
    {MP_ROM_QSTR(MP_QSTR_state), MP_ROM_PTR(&servo_state_obj)},
};
static MP_DEFINE_CONST_DICT(servo_locals, servo_locals_table);

MP_DEFINE_CONST_OBJ_TYPE(
    ob_mp_servo_type,
    MP_QSTR_Servo,
    MP_TYPE_FLAG_NONE,
    make_new, servo_make_new,
    attr, servo_attr,
    locals_dict, &servo_locals,
    parent, &ob_mp_subscriber_type
    );
