/*
 * DriveBase: the 2-DOF drivebase core (host: py_drivebase.c).
 *
 * With the six IO callables (read_left/right() -> degrees or None,
 * write_left/right(duty_pct), coast_left/right()), or with left_io=/right_io=
 * native MotorIOs (a bus engine's slots: no Python per tick, so the hard tick
 * may run it), it is a native motor_process subscriber; with none, update(now_ms, left_deg, right_deg
 * [, heading_deg]) -> (left, right) runs one period with no Python call. A
 * callable that raises must not stop the period (a halt's coast has to reach
 * both motors), so its exception is kept and raised when the period ends, and
 * a read that raised counts as a missing reading, which the watchdog handles.
 */
#include <math.h>

#include "drivebase.h"
#include "mp_bindings.h"

typedef struct _drivebase_obj_t drivebase_obj_t;

/* What a wheel IO callback's ctx points at: the owner and which wheel. */
typedef struct {
    drivebase_obj_t *owner;
    int side;
} wheel_slot_t;

struct _drivebase_obj_t {
    ob_mp_subscriber_t sub;
    ob_drivebase_t db;
    wheel_slot_t slots[2];
    mp_obj_t read[2]; /* MP_OBJ_NULL without IO callables */
    mp_obj_t write[2];
    mp_obj_t coast[2];
    mp_obj_t heading; /* heading source: a callable, a native IMU, or MP_OBJ_NULL */
    ob_heading_source_t native_heading; /* read_heading set when `heading` is a native IMU */
};

/* ---- Arguments. ---- */

static float finite_arg(mp_obj_t obj, const char *where, const char *name) {
    return ob_mp_float(obj, where, name);
}

/* The core refuses a command whose wheel-degrees overflow float (a distance of 1e38 mm): say so. */
static mp_obj_t done_or_refused(bool accepted, const char *where) {
    if (!accepted) {
        mp_raise_msg_varg(&mp_type_ValueError,
                          MP_ERROR_TEXT("%s: the values are too large for the drive base (its wheel-degrees overflow "
                                        "float); nothing was changed"),
                          where);
    }
    return mp_const_none;
}

static ob_then_t then_arg(mp_obj_t obj, const char *where) {
    return obj == MP_OBJ_NULL ? OB_THEN_COAST : ob_mp_then(obj, where);
}

/* ---- IO callables. ---- */

/* An angle from a callable: a number, or None for "no fresh reading". Runs under nlr protection. */
static bool call_angle(drivebase_obj_t *self, mp_obj_t fn, const char *what, float *out) {
    nlr_buf_t nlr;
    if (nlr_push(&nlr) == 0) {
        mp_obj_t result = mp_call_function_0(fn);
        bool fresh = false;
        if (result != mp_const_none) {
            mp_float_t value;
            if (result == mp_const_true || result == mp_const_false || !mp_obj_get_float_maybe(result, &value)) {
                mp_raise_msg_varg(&mp_type_TypeError, MP_ERROR_TEXT("%s must return degrees as a number or None, not %s"),
                                  what, mp_obj_get_type_str(result));
            }
            *out = (float)value;
            fresh = isfinite(value);
        }
        nlr_pop();
        return fresh;
    }
    ob_mp_subscriber_stash(&self->sub, MP_OBJ_FROM_PTR(nlr.ret_val));
    return false;
}

static bool io_read_angle(void *ctx, float *angle_deg) {
    wheel_slot_t *slot = ctx;
    return call_angle(slot->owner, slot->owner->read[slot->side], slot->side == OB_DB_LEFT ? "read_left()" : "read_right()",
                      angle_deg);
}

static void io_write_duty(void *ctx, float duty_pct) {
    wheel_slot_t *slot = ctx;
    nlr_buf_t nlr;
    if (nlr_push(&nlr) == 0) {
        mp_call_function_1(slot->owner->write[slot->side], mp_obj_new_float(duty_pct));
        nlr_pop();
    } else {
        ob_mp_subscriber_stash(&slot->owner->sub, MP_OBJ_FROM_PTR(nlr.ret_val));
    }
}

static void io_write_coast(void *ctx) {
    wheel_slot_t *slot = ctx;
    nlr_buf_t nlr;
    if (nlr_push(&nlr) == 0) {
        mp_call_function_0(slot->owner->coast[slot->side]);
        nlr_pop();
    } else {
        ob_mp_subscriber_stash(&slot->owner->sub, MP_OBJ_FROM_PTR(nlr.ret_val));
    }
}

static bool io_read_heading(void *ctx, float *heading_deg) {
    drivebase_obj_t *self = ctx;
    if (self->heading == MP_OBJ_NULL) {
        return false;
    }
    return call_angle(self, self->heading, "heading()", heading_deg);
}

static void drivebase_tick_fn(void *ctx, uint32_t now_ms) {
    drivebase_obj_t *self = ctx;
    ob_drivebase_tick(&self->db, now_ms); /* callable errors stay in sub.error for motor_process */
}

static bool has_io(const drivebase_obj_t *self) {
    return self->read[0] != MP_OBJ_NULL;
}

/* ---- Construction. ---- */

static mp_obj_t drivebase_make_new(const mp_obj_type_t *type, size_t n_args, size_t n_kw, const mp_obj_t *all_args) {
    enum {
        ARG_wheel_diameter_mm, ARG_axle_track_mm,
        ARG_read_left, ARG_read_right, ARG_write_left, ARG_write_right, ARG_coast_left, ARG_coast_right,
        ARG_heading, ARG_watchdog_ms, ARG_left_io, ARG_right_io,
    };
    static const mp_arg_t allowed[] = {
        {MP_QSTR_wheel_diameter_mm, MP_ARG_REQUIRED | MP_ARG_OBJ, {.u_obj = MP_OBJ_NULL}},
        {MP_QSTR_axle_track_mm, MP_ARG_REQUIRED | MP_ARG_OBJ, {.u_obj = MP_OBJ_NULL}},
        {MP_QSTR_read_left, MP_ARG_KW_ONLY | MP_ARG_OBJ, {.u_obj = mp_const_none}},
        {MP_QSTR_read_right, MP_ARG_KW_ONLY | MP_ARG_OBJ, {.u_obj = mp_const_none}},
        {MP_QSTR_write_left, MP_ARG_KW_ONLY | MP_ARG_OBJ, {.u_obj = mp_const_none}},
        {MP_QSTR_write_right, MP_ARG_KW_ONLY | MP_ARG_OBJ, {.u_obj = mp_const_none}},
        {MP_QSTR_coast_left, MP_ARG_KW_ONLY | MP_ARG_OBJ, {.u_obj = mp_const_none}},
        {MP_QSTR_coast_right, MP_ARG_KW_ONLY | MP_ARG_OBJ, {.u_obj = mp_const_none}},
        {MP_QSTR_heading, MP_ARG_KW_ONLY | MP_ARG_OBJ, {.u_obj = mp_const_none}},
        {MP_QSTR_watchdog_ms, MP_ARG_KW_ONLY | MP_ARG_INT, {.u_int = OB_DB_DEFAULT_WATCHDOG_MS}},
        {MP_QSTR_left_io, MP_ARG_KW_ONLY | MP_ARG_OBJ, {.u_obj = mp_const_none}},
        {MP_QSTR_right_io, MP_ARG_KW_ONLY | MP_ARG_OBJ, {.u_obj = mp_const_none}},
    };
    mp_arg_val_t args[MP_ARRAY_SIZE(allowed)];
    mp_arg_parse_all_kw_array(n_args, n_kw, all_args, MP_ARRAY_SIZE(allowed), allowed, args);
    static const char *where = "DriveBase()";
    float diameter_mm = ob_mp_positive_float(args[ARG_wheel_diameter_mm].u_obj, where, "wheel_diameter_mm");
    float track_mm = ob_mp_positive_float(args[ARG_axle_track_mm].u_obj, where, "axle_track_mm");
    if (args[ARG_watchdog_ms].u_int < 1) {
        mp_raise_ValueError(MP_ERROR_TEXT("DriveBase(): watchdog_ms must be >= 1 ms"));
    }
    mp_obj_t native_io[2] = {args[ARG_left_io].u_obj, args[ARG_right_io].u_obj};
    ob_motor_io_t native_wheel_io[2];
    bool native = native_io[0] != mp_const_none || native_io[1] != mp_const_none;
    for (int i = 0; native && i < 2; i++) {
        if (!ob_mp_motor_io_get(native_io[i], &native_wheel_io[i])) {
            mp_raise_msg_varg(&mp_type_TypeError,
                              MP_ERROR_TEXT("DriveBase(): %s must be a native MotorIO (a bus engine's motor_io(slot)), "
                                            "not %s; give both left_io= and right_io=, or the six IO callables"),
                              i == 0 ? "left_io" : "right_io", mp_obj_get_type_str(native_io[i]));
        }
    }
    static const char *const io_names[6] = {"read_left", "read_right", "write_left", "write_right", "coast_left",
                                            "coast_right"};
    mp_obj_t io[6];
    int given = 0;
    for (int i = 0; i < 6; i++) {
        io[i] = args[ARG_read_left + i].u_obj;
        if (io[i] == mp_const_none) {
            io[i] = MP_OBJ_NULL;
            continue;
        }
        if (!mp_obj_is_callable(io[i])) {
            mp_raise_msg_varg(&mp_type_TypeError, MP_ERROR_TEXT("DriveBase(): %s must be callable, not %s"), io_names[i],
                              mp_obj_get_type_str(io[i]));
        }
        given++;
    }
    if (native && given != 0) {
        mp_raise_TypeError(MP_ERROR_TEXT("DriveBase(): give left_io=/right_io= or the six IO callables, not both"));
    }
    if (given != 0 && given != 6) {
        for (int i = 0; i < 6; i++) {
            if (io[i] == MP_OBJ_NULL) {
                mp_raise_msg_varg(&mp_type_TypeError,
                                  MP_ERROR_TEXT("DriveBase(): give all six IO callables (read_left, read_right, "
                                                "write_left, write_right, coast_left, coast_right) or none (then drive "
                                                "it with update()); %s is missing"),
                                  io_names[i]);
            }
        }
    }
    mp_obj_t heading = args[ARG_heading].u_obj;
    ob_heading_source_t native_heading = {NULL, NULL};
    if (heading != mp_const_none && !ob_mp_icm45686_heading_source(heading, &native_heading) &&
        !mp_obj_is_callable(heading)) {
        mp_raise_msg_varg(&mp_type_TypeError,
                          MP_ERROR_TEXT("DriveBase(): heading must be a callable returning degrees or a native IMU "
                                        "(ICM45686), not %s"),
                          mp_obj_get_type_str(heading));
    }

    drivebase_obj_t *self = mp_obj_malloc(drivebase_obj_t, type);
    self->sub.error = MP_OBJ_NULL;
    self->sub.tick_fn = NULL;
    self->sub.tick_ctx = NULL;
    self->heading = heading == mp_const_none ? MP_OBJ_NULL : heading;
    self->native_heading = native_heading;
    ob_motor_io_t wheel_io[2] = {{0}, {0}};
    for (int i = 0; i < 2; i++) {
        self->slots[i].owner = self;
        self->slots[i].side = i;
        self->read[i] = io[i];
        self->write[i] = io[2 + i];
        self->coast[i] = io[4 + i];
        if (given == 6) {
            wheel_io[i] = (ob_motor_io_t){io_read_angle, io_write_duty, io_write_coast, &self->slots[i]};
        }
    }
    if (native) {
        /* The providers stay referenced through read[] (never called: has_io() only looks at it). */
        for (int i = 0; i < 2; i++) {
            wheel_io[i] = native_wheel_io[i];
            self->read[i] = native_io[i];
        }
    }
    ob_drivebase_init(&self->db, &wheel_io[0], &wheel_io[1], diameter_mm, track_mm);
    self->db.watchdog_ms = (uint32_t)args[ARG_watchdog_ms].u_int;
    if (given == 6 || native) {
        self->sub.tick_fn = drivebase_tick_fn;
        self->sub.tick_ctx = self;
    }
    /* Native wheels and no Python heading (none, or a native IMU read in C): a tick calls no Python, so
     * the hard tick may run it. */
    self->sub.hard_safe = native && (self->heading == MP_OBJ_NULL || native_heading.read_heading != NULL);
    return MP_OBJ_FROM_PTR(self);
}

/* ---- Commands. ---- */

static mp_obj_t drivebase_settings(size_t n_args, const mp_obj_t *pos_args, mp_map_t *kw_args) {
    static const mp_arg_t allowed[] = {
        {MP_QSTR_self, MP_ARG_REQUIRED | MP_ARG_OBJ, {.u_obj = MP_OBJ_NULL}},
        {MP_QSTR_straight_speed, MP_ARG_OBJ, {.u_obj = mp_const_none}},
        {MP_QSTR_turn_rate, MP_ARG_OBJ, {.u_obj = mp_const_none}},
        {MP_QSTR_acceleration, MP_ARG_OBJ, {.u_obj = mp_const_none}},
        {MP_QSTR_turn_acceleration, MP_ARG_OBJ, {.u_obj = mp_const_none}},
    };
    static const char *const names[4] = {"straight_speed (wheel-deg/s)", "turn_rate (wheel-deg/s)",
                                         "acceleration (wheel-deg/s^2)", "turn_acceleration (wheel-deg/s^2)"};
    mp_arg_val_t args[MP_ARRAY_SIZE(allowed)];
    mp_arg_parse_all(n_args, pos_args, kw_args, MP_ARRAY_SIZE(allowed), allowed, args);
    drivebase_obj_t *self = MP_OBJ_TO_PTR(args[0].u_obj);
    float values[4] = {self->db.straight_speed_dps, self->db.turn_rate_dps, self->db.acceleration_dps2,
                       self->db.turn_acceleration_dps2};
    bool any = false;
    for (int i = 0; i < 4; i++) {
        if (args[1 + i].u_obj != mp_const_none) {
            values[i] = ob_mp_positive_float(args[1 + i].u_obj, "DriveBase.settings", names[i]);
            any = true;
        }
    }
    if (!any) {
        mp_obj_t items[4];
        for (int i = 0; i < 4; i++) {
            items[i] = mp_obj_new_float(values[i]);
        }
        return mp_obj_new_tuple(4, items);
    }
    ob_drivebase_settings(&self->db, values[0], values[1], values[2], values[3]);
    return mp_const_none;
}
static MP_DEFINE_CONST_FUN_OBJ_KW(drivebase_settings_obj, 1, drivebase_settings);

/* straight, turn: one value and then=. */
static mp_obj_t one_value_move(size_t n_args, const mp_obj_t *pos_args, mp_map_t *kw_args, qstr value_name, bool turn) {
    const mp_arg_t allowed[] = {
        {MP_QSTR_self, MP_ARG_REQUIRED | MP_ARG_OBJ, {.u_obj = MP_OBJ_NULL}},
        {value_name, MP_ARG_REQUIRED | MP_ARG_OBJ, {.u_obj = MP_OBJ_NULL}},
        {MP_QSTR_then, MP_ARG_OBJ, {.u_obj = MP_OBJ_NULL}},
    };
    mp_arg_val_t args[MP_ARRAY_SIZE(allowed)];
    mp_arg_parse_all(n_args, pos_args, kw_args, MP_ARRAY_SIZE(allowed), allowed, args);
    drivebase_obj_t *self = MP_OBJ_TO_PTR(args[0].u_obj);
    const char *where = turn ? "DriveBase.turn" : "DriveBase.straight";
    float value = finite_arg(args[1].u_obj, where, qstr_str(value_name));
    ob_then_t then = then_arg(args[2].u_obj, where);
    bool accepted = turn ? ob_drivebase_turn(&self->db, value, then) : ob_drivebase_straight(&self->db, value, then);
    return done_or_refused(accepted, where);
}

static mp_obj_t drivebase_straight(size_t n_args, const mp_obj_t *pos_args, mp_map_t *kw_args) {
    return one_value_move(n_args, pos_args, kw_args, MP_QSTR_distance_mm, false);
}
static MP_DEFINE_CONST_FUN_OBJ_KW(drivebase_straight_obj, 1, drivebase_straight);

static mp_obj_t drivebase_turn(size_t n_args, const mp_obj_t *pos_args, mp_map_t *kw_args) {
    return one_value_move(n_args, pos_args, kw_args, MP_QSTR_angle_deg, true);
}
static MP_DEFINE_CONST_FUN_OBJ_KW(drivebase_turn_obj, 1, drivebase_turn);

static mp_obj_t drivebase_curve(size_t n_args, const mp_obj_t *pos_args, mp_map_t *kw_args) {
    static const mp_arg_t allowed[] = {
        {MP_QSTR_self, MP_ARG_REQUIRED | MP_ARG_OBJ, {.u_obj = MP_OBJ_NULL}},
        {MP_QSTR_radius, MP_ARG_REQUIRED | MP_ARG_OBJ, {.u_obj = MP_OBJ_NULL}},
        {MP_QSTR_angle, MP_ARG_REQUIRED | MP_ARG_OBJ, {.u_obj = MP_OBJ_NULL}},
        {MP_QSTR_then, MP_ARG_OBJ, {.u_obj = MP_OBJ_NULL}},
    };
    mp_arg_val_t args[MP_ARRAY_SIZE(allowed)];
    mp_arg_parse_all(n_args, pos_args, kw_args, MP_ARRAY_SIZE(allowed), allowed, args);
    drivebase_obj_t *self = MP_OBJ_TO_PTR(args[0].u_obj);
    static const char *where = "DriveBase.curve";
    float radius_mm = finite_arg(args[1].u_obj, where, "radius (mm)");
    float angle_deg = finite_arg(args[2].u_obj, where, "angle (deg)");
    return done_or_refused(ob_drivebase_curve(&self->db, radius_mm, angle_deg, then_arg(args[3].u_obj, where)), where);
}
static MP_DEFINE_CONST_FUN_OBJ_KW(drivebase_curve_obj, 1, drivebase_curve);

/* drive, move_wheels: two speeds. */
static mp_obj_t two_speeds(size_t n_args, const mp_obj_t *pos_args, mp_map_t *kw_args, qstr a, qstr b, bool wheels) {
    const mp_arg_t allowed[] = {
        {MP_QSTR_self, MP_ARG_REQUIRED | MP_ARG_OBJ, {.u_obj = MP_OBJ_NULL}},
        {a, MP_ARG_REQUIRED | MP_ARG_OBJ, {.u_obj = MP_OBJ_NULL}},
        {b, MP_ARG_REQUIRED | MP_ARG_OBJ, {.u_obj = MP_OBJ_NULL}},
    };
    mp_arg_val_t args[MP_ARRAY_SIZE(allowed)];
    mp_arg_parse_all(n_args, pos_args, kw_args, MP_ARRAY_SIZE(allowed), allowed, args);
    drivebase_obj_t *self = MP_OBJ_TO_PTR(args[0].u_obj);
    const char *where = wheels ? "DriveBase.move_wheels" : "DriveBase.drive";
    float first = finite_arg(args[1].u_obj, where, qstr_str(a));
    float second = finite_arg(args[2].u_obj, where, qstr_str(b));
    bool accepted = wheels ? ob_drivebase_move_wheels(&self->db, first, second)
                           : ob_drivebase_drive(&self->db, first, second);
    return done_or_refused(accepted, where);
}

static mp_obj_t drivebase_drive(size_t n_args, const mp_obj_t *pos_args, mp_map_t *kw_args) {
    return two_speeds(n_args, pos_args, kw_args, MP_QSTR_speed_mm_s, MP_QSTR_turn_rate_dps, false);
}
static MP_DEFINE_CONST_FUN_OBJ_KW(drivebase_drive_obj, 1, drivebase_drive);

static mp_obj_t drivebase_move_wheels(size_t n_args, const mp_obj_t *pos_args, mp_map_t *kw_args) {
    return two_speeds(n_args, pos_args, kw_args, MP_QSTR_left_wheel_speed, MP_QSTR_right_wheel_speed, true);
}
static MP_DEFINE_CONST_FUN_OBJ_KW(drivebase_move_wheels_obj, 1, drivebase_move_wheels);

static mp_obj_t drivebase_stop(size_t n_args, const mp_obj_t *pos_args, mp_map_t *kw_args) {
    static const mp_arg_t allowed[] = {
        {MP_QSTR_self, MP_ARG_REQUIRED | MP_ARG_OBJ, {.u_obj = MP_OBJ_NULL}},
        {MP_QSTR_then, MP_ARG_OBJ, {.u_obj = MP_OBJ_NULL}},
    };
    mp_arg_val_t args[MP_ARRAY_SIZE(allowed)];
    mp_arg_parse_all(n_args, pos_args, kw_args, MP_ARRAY_SIZE(allowed), allowed, args);
    drivebase_obj_t *self = MP_OBJ_TO_PTR(args[0].u_obj);
    ob_drivebase_stop(&self->db, then_arg(args[1].u_obj, "DriveBase.stop"));
    ob_mp_subscriber_raise(&self->sub); /* a coast callable raised */
    return mp_const_none;
}
static MP_DEFINE_CONST_FUN_OBJ_KW(drivebase_stop_obj, 1, drivebase_stop);

static mp_obj_t drivebase_reset(mp_obj_t self_in) {
    drivebase_obj_t *self = MP_OBJ_TO_PTR(self_in);
    if (!ob_drivebase_reset(&self->db)) {
        mp_raise_msg(&mp_type_RuntimeError,
                     MP_ERROR_TEXT("DriveBase.reset() refused: a move is in progress; call stop() or wait for done() first"));
    }
    return mp_const_none;
}
static MP_DEFINE_CONST_FUN_OBJ_1(drivebase_reset_obj, drivebase_reset);

static mp_obj_t drivebase_use_gyro(mp_obj_t self_in, mp_obj_t enable_in) {
    drivebase_obj_t *self = MP_OBJ_TO_PTR(self_in);
    if (!mp_obj_is_true(enable_in)) {
        ob_drivebase_use_gyro(&self->db, NULL);
        return mp_const_none;
    }
    if (has_io(self) && self->heading == MP_OBJ_NULL) {
        mp_raise_ValueError(MP_ERROR_TEXT("use_gyro(True) needs a heading source: pass heading=<callable returning "
                                          "degrees, or a native ICM45686> to DriveBase(...)"));
    }
    /* Without IO callables the heading arrives through update(..., heading_deg); a native IMU is read in C. */
    ob_heading_source_t source = {self->heading != MP_OBJ_NULL ? io_read_heading : NULL, self};
    if (self->native_heading.read_heading != NULL) {
        source = self->native_heading;
    }
    ob_drivebase_use_gyro(&self->db, &source);
    return mp_const_none;
}
static MP_DEFINE_CONST_FUN_OBJ_2(drivebase_use_gyro_obj, drivebase_use_gyro);

/* The watchdog's halt as an OSError saying which feedback went silent and what to check. */
static MP_NORETURN void raise_fault(const drivebase_obj_t *self) {
    uint8_t fault = ob_drivebase_fault(&self->db);
    const char *which = (fault & OB_DB_FAULT_LEFT) && (fault & OB_DB_FAULT_RIGHT) ? "both wheels"
                        : (fault & OB_DB_FAULT_LEFT)                              ? "the left wheel"
                        : (fault & OB_DB_FAULT_RIGHT)                             ? "the right wheel"
                                                                                  : "the gyro";
    mp_raise_msg_varg(&mp_type_OSError,
                      MP_ERROR_TEXT("DriveBase halted: no reading from %s for more than %u ms, so both wheels were "
                                    "released instead of chasing a frozen position. Check that motor's power and "
                                    "wiring (or the IMU's); the next move retries."),
                      which, (unsigned)self->db.watchdog_ms);
}

static mp_obj_t drivebase_done(mp_obj_t self_in) {
    drivebase_obj_t *self = MP_OBJ_TO_PTR(self_in);
    if (ob_drivebase_fault(&self->db) != 0) {
        raise_fault(self);
    }
    return mp_obj_new_bool(ob_drivebase_done(&self->db));
}
static MP_DEFINE_CONST_FUN_OBJ_1(drivebase_done_obj, drivebase_done);

static mp_obj_t drivebase_fault(mp_obj_t self_in) {
    drivebase_obj_t *self = MP_OBJ_TO_PTR(self_in);
    uint8_t fault = ob_drivebase_fault(&self->db);
    if (fault == 0) {
        return mp_const_none;
    }
    mp_obj_t names[3];
    size_t n = 0;
    if (fault & OB_DB_FAULT_LEFT) {
        names[n++] = MP_OBJ_NEW_QSTR(MP_QSTR_left);
    }
    if (fault & OB_DB_FAULT_RIGHT) {
        names[n++] = MP_OBJ_NEW_QSTR(MP_QSTR_right);
    }
    if (fault & OB_DB_FAULT_GYRO) {
        names[n++] = MP_OBJ_NEW_QSTR(MP_QSTR_gyro);
    }
    return mp_obj_new_tuple(n, names);
}
static MP_DEFINE_CONST_FUN_OBJ_1(drivebase_fault_obj, drivebase_fault);

static mp_obj_t drivebase_state(mp_obj_t self_in) {
    drivebase_obj_t *self = MP_OBJ_TO_PTR(self_in);
    ob_drivebase_state_t st;
    ob_drivebase_get_state(&self->db, &st);
    mp_obj_t items[4] = {mp_obj_new_float(st.distance_mm), mp_obj_new_float(st.drive_speed_mm_s),
                         mp_obj_new_float(st.angle_deg), mp_obj_new_float(st.turn_rate_dps)};
    return mp_obj_new_tuple(4, items);
}
static MP_DEFINE_CONST_FUN_OBJ_1(drivebase_state_obj, drivebase_state);

static mp_obj_t drivebase_distance(mp_obj_t self_in) {
    drivebase_obj_t *self = MP_OBJ_TO_PTR(self_in);
    ob_drivebase_state_t st;
    ob_drivebase_get_state(&self->db, &st);
    return mp_obj_new_float(st.distance_mm);
}
static MP_DEFINE_CONST_FUN_OBJ_1(drivebase_distance_obj, drivebase_distance);

static mp_obj_t drivebase_angle(mp_obj_t self_in) {
    drivebase_obj_t *self = MP_OBJ_TO_PTR(self_in);
    ob_drivebase_state_t st;
    ob_drivebase_get_state(&self->db, &st);
    return mp_obj_new_float(st.angle_deg);
}
static MP_DEFINE_CONST_FUN_OBJ_1(drivebase_angle_obj, drivebase_angle);

/* ---- Control periods. ---- */

/* A reading for update(): a number, or None for "no fresh reading this period". */
static void reading_arg(mp_obj_t obj, const char *name, bool *ok, float *value) {
    if (obj == mp_const_none) {
        *ok = false;
        *value = 0.0f;
        return;
    }
    mp_float_t v;
    if (obj == mp_const_true || obj == mp_const_false || !mp_obj_get_float_maybe(obj, &v)) {
        mp_raise_msg_varg(&mp_type_TypeError, MP_ERROR_TEXT("DriveBase.update: %s must be degrees (a number) or None, not %s"),
                          name, mp_obj_get_type_str(obj));
    }
    *ok = isfinite(v);
    *value = (float)v;
}

static mp_obj_t duty_or_none(const ob_drivebase_output_t *out, int side) {
    return out->coast[side] ? mp_const_none : mp_obj_new_float(out->duty_pct[side]);
}

static mp_obj_t drivebase_update(size_t n_args, const mp_obj_t *args) {
    drivebase_obj_t *self = MP_OBJ_TO_PTR(args[0]);
    /* Unlike the other time arguments this one wraps rather than refuses: it is the simulator's per-step call. */
    if (!mp_obj_is_int(args[1])) {
        mp_raise_msg_varg(&mp_type_TypeError, MP_ERROR_TEXT("DriveBase.update: now_ms must be an int (milliseconds), not %s"),
                          mp_obj_get_type_str(args[1]));
    }
    uint32_t now_ms = (uint32_t)mp_obj_get_int_truncated(args[1]);
    ob_drivebase_feedback_t fb;
    reading_arg(args[2], "left_deg", &fb.wheel_ok[OB_DB_LEFT], &fb.wheel_deg[OB_DB_LEFT]);
    reading_arg(args[3], "right_deg", &fb.wheel_ok[OB_DB_RIGHT], &fb.wheel_deg[OB_DB_RIGHT]);
    fb.heading_ok = false;
    fb.heading_deg = 0.0f;
    if (n_args == 5) {
        reading_arg(args[4], "heading_deg", &fb.heading_ok, &fb.heading_deg);
    } else if (self->db.use_gyro) {
        mp_raise_TypeError(MP_ERROR_TEXT("DriveBase.update: use_gyro(True) is on, so pass heading_deg (or None for a "
                                         "missed sample) as the fourth argument"));
    }
    ob_drivebase_output_t out;
    ob_drivebase_step(&self->db, now_ms, &fb, &out);
    mp_obj_t items[2] = {duty_or_none(&out, OB_DB_LEFT), duty_or_none(&out, OB_DB_RIGHT)};
    return mp_obj_new_tuple(2, items);
}
static MP_DEFINE_CONST_FUN_OBJ_VAR_BETWEEN(drivebase_update_obj, 4, 5, drivebase_update);

static mp_obj_t drivebase_tick(mp_obj_t self_in, mp_obj_t now_in) {
    drivebase_obj_t *self = MP_OBJ_TO_PTR(self_in);
    if (!has_io(self)) {
        mp_raise_ValueError(MP_ERROR_TEXT("tick() runs through the IO callables and this DriveBase has none; use "
                                          "update(now_ms, left_deg, right_deg) instead"));
    }
    ob_drivebase_tick(&self->db, ob_mp_time_ms(now_in, "DriveBase.tick"));
    ob_mp_subscriber_raise(&self->sub);
    return mp_const_none;
}
static MP_DEFINE_CONST_FUN_OBJ_2(drivebase_tick_obj, drivebase_tick);

static const mp_rom_map_elem_t drivebase_locals_table[] = {
    {MP_ROM_QSTR(MP_QSTR_settings), MP_ROM_PTR(&drivebase_settings_obj)},
    {MP_ROM_QSTR(MP_QSTR_straight), MP_ROM_PTR(&drivebase_straight_obj)},
    {MP_ROM_QSTR(MP_QSTR_turn), MP_ROM_PTR(&drivebase_turn_obj)},
    {MP_ROM_QSTR(MP_QSTR_curve), MP_ROM_PTR(&drivebase_curve_obj)},
    {MP_ROM_QSTR(MP_QSTR_drive), MP_ROM_PTR(&drivebase_drive_obj)},
    {MP_ROM_QSTR(MP_QSTR_move_wheels), MP_ROM_PTR(&drivebase_move_wheels_obj)},
    {MP_ROM_QSTR(MP_QSTR_stop), MP_ROM_PTR(&drivebase_stop_obj)},
    {MP_ROM_QSTR(MP_QSTR_reset), MP_ROM_PTR(&drivebase_reset_obj)},
    {MP_ROM_QSTR(MP_QSTR_use_gyro), MP_ROM_PTR(&drivebase_use_gyro_obj)},
    {MP_ROM_QSTR(MP_QSTR_done), MP_ROM_PTR(&drivebase_done_obj)},
    {MP_ROM_QSTR(MP_QSTR_fault), MP_ROM_PTR(&drivebase_fault_obj)},
    {MP_ROM_QSTR(MP_QSTR_state), MP_ROM_PTR(&drivebase_state_obj)},
    {MP_ROM_QSTR(MP_QSTR_distance), MP_ROM_PTR(&drivebase_distance_obj)},
    {MP_ROM_QSTR(MP_QSTR_angle), MP_ROM_PTR(&drivebase_angle_obj)},
    {MP_ROM_QSTR(MP_QSTR_update), MP_ROM_PTR(&drivebase_update_obj)},
    {MP_ROM_QSTR(MP_QSTR_tick), MP_ROM_PTR(&drivebase_tick_obj)},
};
static MP_DEFINE_CONST_DICT(drivebase_locals, drivebase_locals_table);

/* Methods run under the motor lock: the hard tick may be ticking this drive base (mp_hard_lock.c). */
static void drivebase_attr(mp_obj_t self_in, qstr attr, mp_obj_t *dest) {
    ob_mp_locked_attr(self_in, attr, dest, &drivebase_locals);
}

MP_DEFINE_CONST_OBJ_TYPE(
    ob_mp_drivebase_type,
    MP_QSTR_DriveBase,
    MP_TYPE_FLAG_NONE,
    make_new, drivebase_make_new,
    attr, drivebase_attr,
    locals_dict, &drivebase_locals,
    parent, &ob_mp_subscriber_type
    );
