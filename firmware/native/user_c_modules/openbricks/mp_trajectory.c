/*
 * TrapezoidalProfile: the trajectory core as an immutable object (host: py_trajectory.c).
 */
#include "mp_bindings.h"
#include "trajectory.h"

typedef struct {
    mp_obj_base_t base;
    ob_trajectory_t tr;
} profile_obj_t;

static mp_obj_t profile_wrap(const ob_trajectory_t *tr) {
    profile_obj_t *self = mp_obj_malloc(profile_obj_t, &ob_mp_profile_type);
    self->tr = *tr;
    return MP_OBJ_FROM_PTR(self);
}

static mp_obj_t profile_make_new(const mp_obj_type_t *type, size_t n_args, size_t n_kw, const mp_obj_t *all_args) {
    (void)type;
    enum { ARG_x0_deg, ARG_target_deg, ARG_speed_dps, ARG_accel_dps2, ARG_decel_dps2, ARG_v0_dps, ARG_end_at_cruise };
    static const mp_arg_t allowed[] = {
        {MP_QSTR_x0_deg, MP_ARG_REQUIRED | MP_ARG_OBJ, {.u_obj = MP_OBJ_NULL}},
        {MP_QSTR_target_deg, MP_ARG_REQUIRED | MP_ARG_OBJ, {.u_obj = MP_OBJ_NULL}},
        {MP_QSTR_speed_dps, MP_ARG_REQUIRED | MP_ARG_OBJ, {.u_obj = MP_OBJ_NULL}},
        {MP_QSTR_accel_dps2, MP_ARG_REQUIRED | MP_ARG_OBJ, {.u_obj = MP_OBJ_NULL}},
        {MP_QSTR_decel_dps2, MP_ARG_OBJ, {.u_obj = mp_const_none}},
        {MP_QSTR_v0_dps, MP_ARG_OBJ, {.u_obj = MP_OBJ_NULL}},
        {MP_QSTR_end_at_cruise, MP_ARG_KW_ONLY | MP_ARG_BOOL, {.u_bool = false}},
    };
    mp_arg_val_t args[MP_ARRAY_SIZE(allowed)];
    mp_arg_parse_all_kw_array(n_args, n_kw, all_args, MP_ARRAY_SIZE(allowed), allowed, args);
    static const char *where = "TrapezoidalProfile";
    float x0 = ob_mp_float(args[ARG_x0_deg].u_obj, where, "x0_deg");
    float target = ob_mp_float(args[ARG_target_deg].u_obj, where, "target_deg");
    float speed = ob_mp_positive_float(args[ARG_speed_dps].u_obj, where, "speed_dps");
    float accel = ob_mp_positive_float(args[ARG_accel_dps2].u_obj, where, "accel_dps2");
    float decel = accel;
    if (ob_mp_given(args[ARG_decel_dps2].u_obj)) {
        decel = ob_mp_positive_float(args[ARG_decel_dps2].u_obj, where, "decel_dps2");
    }
    float v0 = 0.0f;
    if (ob_mp_given(args[ARG_v0_dps].u_obj)) {
        v0 = ob_mp_float(args[ARG_v0_dps].u_obj, where, "v0_dps");
    }
    ob_trajectory_t tr;
    ob_trajectory_plan_move(&tr, x0, v0, target, speed, accel, decel, args[ARG_end_at_cruise].u_bool);
    return profile_wrap(&tr);
}

static mp_obj_t profile_speed_ramp(size_t n_args, const mp_obj_t *pos_args, mp_map_t *kw_args) {
    enum { ARG_cls, ARG_x0_deg, ARG_v0_dps, ARG_speed_dps, ARG_accel_dps2 };
    static const mp_arg_t allowed[] = {
        {MP_QSTR_cls, MP_ARG_REQUIRED | MP_ARG_OBJ, {.u_obj = MP_OBJ_NULL}},
        {MP_QSTR_x0_deg, MP_ARG_REQUIRED | MP_ARG_OBJ, {.u_obj = MP_OBJ_NULL}},
        {MP_QSTR_v0_dps, MP_ARG_REQUIRED | MP_ARG_OBJ, {.u_obj = MP_OBJ_NULL}},
        {MP_QSTR_speed_dps, MP_ARG_REQUIRED | MP_ARG_OBJ, {.u_obj = MP_OBJ_NULL}},
        {MP_QSTR_accel_dps2, MP_ARG_REQUIRED | MP_ARG_OBJ, {.u_obj = MP_OBJ_NULL}},
    };
    mp_arg_val_t args[MP_ARRAY_SIZE(allowed)];
    mp_arg_parse_all(n_args, pos_args, kw_args, MP_ARRAY_SIZE(allowed), allowed, args);
    static const char *where = "TrapezoidalProfile.speed_ramp";
    ob_trajectory_t tr;
    ob_trajectory_plan_speed(&tr, ob_mp_float(args[ARG_x0_deg].u_obj, where, "x0_deg"),
                             ob_mp_float(args[ARG_v0_dps].u_obj, where, "v0_dps"),
                             ob_mp_float(args[ARG_speed_dps].u_obj, where, "speed_dps"),
                             ob_mp_positive_float(args[ARG_accel_dps2].u_obj, where, "accel_dps2"));
    return profile_wrap(&tr);
}
static MP_DEFINE_CONST_FUN_OBJ_KW(profile_speed_ramp_fun_obj, 1, profile_speed_ramp);
static MP_DEFINE_CONST_CLASSMETHOD_OBJ(profile_speed_ramp_obj, MP_ROM_PTR(&profile_speed_ramp_fun_obj));

static mp_obj_t profile_hold(mp_obj_t cls, mp_obj_t x_in) {
    (void)cls;
    ob_trajectory_t tr;
    ob_trajectory_plan_hold(&tr, ob_mp_float(x_in, "TrapezoidalProfile.hold", "x_deg"));
    return profile_wrap(&tr);
}
static MP_DEFINE_CONST_FUN_OBJ_2(profile_hold_fun_obj, profile_hold);
static MP_DEFINE_CONST_CLASSMETHOD_OBJ(profile_hold_obj, MP_ROM_PTR(&profile_hold_fun_obj));

static mp_obj_t profile_sample(mp_obj_t self_in, mp_obj_t t_in) {
    profile_obj_t *self = MP_OBJ_TO_PTR(self_in);
    ob_trajectory_sample_t out;
    ob_trajectory_sample(&self->tr, ob_mp_float(t_in, "TrapezoidalProfile.sample", "t_s"), &out);
    mp_obj_t items[3] = {mp_obj_new_float(out.x_deg), mp_obj_new_float(out.v_dps), mp_obj_new_float(out.a_dps2)};
    return mp_obj_new_tuple(3, items);
}
static MP_DEFINE_CONST_FUN_OBJ_2(profile_sample_obj, profile_sample);

static mp_obj_t profile_scaled(size_t n_args, const mp_obj_t *pos_args, mp_map_t *kw_args) {
    enum { ARG_self, ARG_k, ARG_x0_deg };
    static const mp_arg_t allowed[] = {
        {MP_QSTR_self, MP_ARG_REQUIRED | MP_ARG_OBJ, {.u_obj = MP_OBJ_NULL}},
        {MP_QSTR_k, MP_ARG_REQUIRED | MP_ARG_OBJ, {.u_obj = MP_OBJ_NULL}},
        {MP_QSTR_x0_deg, MP_ARG_REQUIRED | MP_ARG_OBJ, {.u_obj = MP_OBJ_NULL}},
    };
    mp_arg_val_t args[MP_ARRAY_SIZE(allowed)];
    mp_arg_parse_all(n_args, pos_args, kw_args, MP_ARRAY_SIZE(allowed), allowed, args);
    profile_obj_t *self = MP_OBJ_TO_PTR(args[ARG_self].u_obj);
    static const char *where = "TrapezoidalProfile.scaled";
    ob_trajectory_t tr;
    ob_trajectory_scaled(&self->tr, ob_mp_float(args[ARG_k].u_obj, where, "k"),
                         ob_mp_float(args[ARG_x0_deg].u_obj, where, "x0_deg"), &tr);
    return profile_wrap(&tr);
}
static MP_DEFINE_CONST_FUN_OBJ_KW(profile_scaled_obj, 1, profile_scaled);

static mp_obj_t float_tuple(const float *values, size_t n) {
    mp_obj_t items[4];
    for (size_t i = 0; i < n; i++) {
        items[i] = mp_obj_new_float(values[i]);
    }
    return mp_obj_new_tuple(n, items);
}

/* The host's read-only properties. */
static void profile_attr(mp_obj_t self_in, qstr attr, mp_obj_t *dest) {
    if (dest[0] != MP_OBJ_NULL) {
        return; /* immutable: no stores, no deletes */
    }
    profile_obj_t *self = MP_OBJ_TO_PTR(self_in);
    switch (attr) {
        case MP_QSTR_duration_s:
            dest[0] = mp_obj_new_float(ob_trajectory_duration_s(&self->tr));
            break;
        case MP_QSTR_end_deg:
            dest[0] = mp_obj_new_float(ob_trajectory_end_deg(&self->tr));
            break;
        case MP_QSTR_phase_end_s:
            dest[0] = float_tuple(self->tr.t_s, 3);
            break;
        case MP_QSTR_phase_x_deg:
            dest[0] = float_tuple(self->tr.x_deg, 4);
            break;
        case MP_QSTR_phase_v_dps:
            dest[0] = float_tuple(self->tr.v_dps, 4);
            break;
        case MP_QSTR_phase_a_dps2:
            dest[0] = float_tuple(self->tr.a_dps2, 3);
            break;
        default:
            dest[1] = MP_OBJ_SENTINEL; /* continue in locals_dict */
            break;
    }
}

static void profile_print(const mp_print_t *print, mp_obj_t self_in, mp_print_kind_t kind) {
    (void)kind;
    profile_obj_t *self = MP_OBJ_TO_PTR(self_in);
    mp_printf(print, "TrapezoidalProfile(%g deg -> %g deg in %g s, tail %g deg/s)", (double)self->tr.x_deg[0],
              (double)self->tr.x_deg[3], (double)self->tr.t_s[2], (double)self->tr.v_dps[3]);
}

static const mp_rom_map_elem_t profile_locals_table[] = {
    {MP_ROM_QSTR(MP_QSTR_sample), MP_ROM_PTR(&profile_sample_obj)},
    {MP_ROM_QSTR(MP_QSTR_scaled), MP_ROM_PTR(&profile_scaled_obj)},
    {MP_ROM_QSTR(MP_QSTR_speed_ramp), MP_ROM_PTR(&profile_speed_ramp_obj)},
    {MP_ROM_QSTR(MP_QSTR_hold), MP_ROM_PTR(&profile_hold_obj)},
};
static MP_DEFINE_CONST_DICT(profile_locals, profile_locals_table);

MP_DEFINE_CONST_OBJ_TYPE(
    ob_mp_profile_type,
    MP_QSTR_TrapezoidalProfile,
    MP_TYPE_FLAG_NONE,
    make_new, profile_make_new,
    print, profile_print,
    attr, profile_attr,
    locals_dict, &profile_locals
    );
