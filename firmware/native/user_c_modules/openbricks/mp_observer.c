/*
 * Observer: the alpha-beta estimator on its own (host: py_observer.c).
 */
#include "mp_bindings.h"
#include "observer.h"

typedef struct {
    mp_obj_base_t base;
    ob_observer_t ob;
} observer_obj_t;

static float gain_arg(mp_obj_t obj, const char *name) {
    float gain = ob_mp_float(obj, "Observer", name);
    if (!(gain > 0.0f && gain <= 1.0f)) {
        mp_raise_msg_varg(&mp_type_ValueError, MP_ERROR_TEXT("Observer: %s must be within (0, 1], got %f"), name,
                          (double)gain);
    }
    return gain;
}

static float dt_arg(mp_obj_t obj, const char *where) {
    float dt = ob_mp_float(obj, where, "dt_s");
    if (dt < 0.0f) {
        mp_raise_msg_varg(&mp_type_ValueError, MP_ERROR_TEXT("%s: dt_s must be >= 0, got %f"), where, (double)dt);
    }
    return dt;
}

static mp_obj_t observer_state(const observer_obj_t *self) {
    mp_obj_t items[2] = {mp_obj_new_float(self->ob.x_deg), mp_obj_new_float(self->ob.v_dps)};
    return mp_obj_new_tuple(2, items);
}

static mp_obj_t observer_make_new(const mp_obj_type_t *type, size_t n_args, size_t n_kw, const mp_obj_t *all_args) {
    enum { ARG_alpha, ARG_beta, ARG_x_deg };
    static const mp_arg_t allowed[] = {
        {MP_QSTR_alpha, MP_ARG_OBJ, {.u_obj = MP_OBJ_NULL}},
        {MP_QSTR_beta, MP_ARG_OBJ, {.u_obj = MP_OBJ_NULL}},
        {MP_QSTR_x_deg, MP_ARG_OBJ, {.u_obj = MP_OBJ_NULL}},
    };
    mp_arg_val_t args[MP_ARRAY_SIZE(allowed)];
    mp_arg_parse_all_kw_array(n_args, n_kw, all_args, MP_ARRAY_SIZE(allowed), allowed, args);
    float alpha = OB_OBSERVER_DEFAULT_ALPHA, beta = OB_OBSERVER_DEFAULT_BETA, x = 0.0f;
    if (args[ARG_alpha].u_obj != MP_OBJ_NULL) {
        alpha = gain_arg(args[ARG_alpha].u_obj, "alpha");
    }
    if (args[ARG_beta].u_obj != MP_OBJ_NULL) {
        beta = gain_arg(args[ARG_beta].u_obj, "beta");
    }
    if (args[ARG_x_deg].u_obj != MP_OBJ_NULL) {
        x = ob_mp_float(args[ARG_x_deg].u_obj, "Observer", "x_deg");
    }
    observer_obj_t *self = mp_obj_malloc(observer_obj_t, type);
    ob_observer_init(&self->ob, alpha, beta);
    ob_observer_reset(&self->ob, x);
    return MP_OBJ_FROM_PTR(self);
}

static mp_obj_t observer_update(mp_obj_t self_in, mp_obj_t measured_in, mp_obj_t dt_in) {
    observer_obj_t *self = MP_OBJ_TO_PTR(self_in);
    static const char *where = "Observer.update";
    float measured = ob_mp_float(measured_in, where, "measured_deg");
    ob_observer_update(&self->ob, measured, dt_arg(dt_in, where));
    return observer_state(self);
}
static MP_DEFINE_CONST_FUN_OBJ_3(observer_update_obj, observer_update);

static mp_obj_t observer_predict(mp_obj_t self_in, mp_obj_t dt_in) {
    observer_obj_t *self = MP_OBJ_TO_PTR(self_in);
    ob_observer_predict(&self->ob, dt_arg(dt_in, "Observer.predict"));
    return observer_state(self);
}
static MP_DEFINE_CONST_FUN_OBJ_2(observer_predict_obj, observer_predict);

static mp_obj_t observer_reset(size_t n_args, const mp_obj_t *pos_args, mp_map_t *kw_args) {
    enum { ARG_self, ARG_x_deg };
    static const mp_arg_t allowed[] = {
        {MP_QSTR_self, MP_ARG_REQUIRED | MP_ARG_OBJ, {.u_obj = MP_OBJ_NULL}},
        {MP_QSTR_x_deg, MP_ARG_OBJ, {.u_obj = MP_OBJ_NULL}},
    };
    mp_arg_val_t args[MP_ARRAY_SIZE(allowed)];
    mp_arg_parse_all(n_args, pos_args, kw_args, MP_ARRAY_SIZE(allowed), allowed, args);
    observer_obj_t *self = MP_OBJ_TO_PTR(args[ARG_self].u_obj);
    float x = 0.0f;
    if (args[ARG_x_deg].u_obj != MP_OBJ_NULL) {
        x = ob_mp_float(args[ARG_x_deg].u_obj, "Observer.reset", "x_deg");
    }
    ob_observer_reset(&self->ob, x);
    return mp_const_none;
}
static MP_DEFINE_CONST_FUN_OBJ_KW(observer_reset_obj, 1, observer_reset);

static void observer_attr(mp_obj_t self_in, qstr attr, mp_obj_t *dest) {
    if (dest[0] != MP_OBJ_NULL) {
        return; /* read-only */
    }
    observer_obj_t *self = MP_OBJ_TO_PTR(self_in);
    switch (attr) {
        case MP_QSTR_x_deg:
            dest[0] = mp_obj_new_float(self->ob.x_deg);
            break;
        case MP_QSTR_v_dps:
            dest[0] = mp_obj_new_float(self->ob.v_dps);
            break;
        case MP_QSTR_alpha:
            dest[0] = mp_obj_new_float(self->ob.alpha);
            break;
        case MP_QSTR_beta:
            dest[0] = mp_obj_new_float(self->ob.beta);
            break;
        default:
            dest[1] = MP_OBJ_SENTINEL;
            break;
    }
}

static const mp_rom_map_elem_t observer_locals_table[] = {
    {MP_ROM_QSTR(MP_QSTR_update), MP_ROM_PTR(&observer_update_obj)},
    {MP_ROM_QSTR(MP_QSTR_predict), MP_ROM_PTR(&observer_predict_obj)},
    {MP_ROM_QSTR(MP_QSTR_reset), MP_ROM_PTR(&observer_reset_obj)},
};
static MP_DEFINE_CONST_DICT(observer_locals, observer_locals_table);

MP_DEFINE_CONST_OBJ_TYPE(
    ob_mp_observer_type,
    MP_QSTR_Observer,
    MP_TYPE_FLAG_NONE,
    make_new, observer_make_new,
    attr, observer_attr,
    locals_dict, &observer_locals
    );
