/*
 * Argument checks shared by the MicroPython bindings (the host's py_args.h).
 */
#include <math.h>
#include <string.h>

#include "py/objint.h"

#include "mp_bindings.h"

static bool is_bool(mp_obj_t obj) {
    return obj == mp_const_true || obj == mp_const_false;
}

float ob_mp_float(mp_obj_t obj, const char *where, const char *name) {
    mp_float_t value;
    if (is_bool(obj) || mp_obj_is_str(obj) || !mp_obj_get_float_maybe(obj, &value)) {
        mp_raise_msg_varg(&mp_type_TypeError, MP_ERROR_TEXT("%s: %s must be a number, not %s"), where, name,
                          mp_obj_get_type_str(obj));
    }
    if (!isfinite(value) || value > (mp_float_t)3.0e38 || value < (mp_float_t)-3.0e38) {
        mp_raise_msg_varg(&mp_type_ValueError, MP_ERROR_TEXT("%s: %s must be a finite number"), where, name);
    }
    return (float)value;
}

float ob_mp_positive_float(mp_obj_t obj, const char *where, const char *name) {
    float value = ob_mp_float(obj, where, name);
    if (!(value > 0.0f)) {
        mp_raise_msg_varg(&mp_type_ValueError, MP_ERROR_TEXT("%s: %s must be > 0, got %f"), where, name,
                          (double)value);
    }
    return value;
}

int32_t ob_mp_int32(mp_obj_t obj, const char *where, const char *name) {
    if (is_bool(obj) || !mp_obj_is_int(obj)) {
        mp_raise_msg_varg(&mp_type_TypeError, MP_ERROR_TEXT("%s: %s must be an int, not %s"), where, name,
                          mp_obj_get_type_str(obj));
    }
    mp_int_t value;
    if (!mp_obj_get_int_maybe(obj, &value) || (mp_int_t)(int32_t)value != value) {
        mp_raise_msg_varg(&mp_type_ValueError, MP_ERROR_TEXT("%s: %s is out of range (a 32-bit count)"), where, name);
    }
    return (int32_t)value;
}

uint32_t ob_mp_time_ms(mp_obj_t obj, const char *where) {
    if (is_bool(obj) || !mp_obj_is_int(obj)) {
        /* Floats are refused, not truncated: a fractional millisecond is a caller's bug. */
        mp_raise_msg_varg(&mp_type_TypeError, MP_ERROR_TEXT("%s: now_ms must be an int (milliseconds), not %s"),
                          where, mp_obj_get_type_str(obj));
    }
    if (mp_obj_int_sign(obj) < 0) {
        mp_raise_msg_varg(&mp_type_ValueError, MP_ERROR_TEXT("%s: now_ms must be >= 0"), where);
    }
    return (uint32_t)mp_obj_get_int_truncated(obj);
}

static const struct {
    const char *name;
    ob_then_t then;
} then_names[] = {
    {"coast", OB_THEN_COAST}, {"stop", OB_THEN_COAST},         {"brake", OB_THEN_BRAKE},
    {"hold", OB_THEN_HOLD},   {"continue", OB_THEN_CONTINUE},
};

ob_then_t ob_mp_then(mp_obj_t obj, const char *where) {
    if (!mp_obj_is_str(obj)) {
        mp_raise_msg_varg(&mp_type_TypeError,
                          MP_ERROR_TEXT("%s: then must be one of 'coast', 'stop', 'brake', 'hold', 'continue', not %s"),
                          where, mp_obj_get_type_str(obj));
    }
    const char *text = mp_obj_str_get_str(obj);
    for (size_t i = 0; i < MP_ARRAY_SIZE(then_names); i++) {
        if (strcmp(text, then_names[i].name) == 0) {
            return then_names[i].then;
        }
    }
    mp_raise_msg_varg(&mp_type_ValueError,
                      MP_ERROR_TEXT("%s: then must be one of 'coast', 'stop', 'brake', 'hold', 'continue', got '%s'"),
                      where, text);
}

const char *ob_mp_then_name(ob_then_t then) {
    switch (then) {
        case OB_THEN_BRAKE:
            return "brake";
        case OB_THEN_HOLD:
            return "hold";
        case OB_THEN_CONTINUE:
            return "continue";
        case OB_THEN_COAST:
        default:
            return "coast";
    }
}
