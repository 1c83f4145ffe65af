/*
 * MotorIO and the native UART base: how a binding object hands a controller
 * or the serial-bus engine C functions that never call Python (host: the
 * MotorIO of py_capi.c / py_motor_io.h).
 *
 * A provider's object struct starts with ob_mp_motor_io_t (or
 * ob_mp_native_uart_t) and its type names ob_mp_motor_io_type (or
 * ob_mp_native_uart_type) as parent; a consumer copies the functions out
 * and keeps a reference to the object for as long as it calls them.
 */
#include "mp_bindings.h"
#include "py/objtype.h"

/* obj as an object of `base`: a native type deriving from it shares its layout, a Python subclass
 * instance holds it as its native part; MP_OBJ_NULL for anything else. */
static mp_obj_t native_base(mp_obj_t obj, const mp_obj_type_t *base) {
    const mp_obj_type_t *type = mp_obj_get_type(obj);
    if (!mp_obj_is_subclass_fast(MP_OBJ_FROM_PTR(type), MP_OBJ_FROM_PTR(base))) {
        return MP_OBJ_NULL;
    }
    if (mp_obj_is_instance_type(type)) {
        return mp_obj_cast_to_native_base(obj, MP_OBJ_FROM_PTR(base));
    }
    return obj;
}

MP_DEFINE_CONST_OBJ_TYPE(
    ob_mp_motor_io_type,
    MP_QSTR_MotorIO,
    MP_TYPE_FLAG_NONE
    );

bool ob_mp_motor_io_get(mp_obj_t obj, ob_motor_io_t *io) {
    mp_obj_t base = native_base(obj, &ob_mp_motor_io_type);
    if (base == MP_OBJ_NULL) {
        return false;
    }
    const ob_mp_motor_io_t *provider = MP_OBJ_TO_PTR(base);
    if (provider->io.read_angle == NULL || provider->io.write_duty == NULL || provider->io.write_coast == NULL) {
        return false;
    }
    *io = provider->io;
    return true;
}

MP_DEFINE_CONST_OBJ_TYPE(
    ob_mp_native_uart_type,
    MP_QSTR_NativeUART,
    MP_TYPE_FLAG_NONE
    );

const ob_uart_t *ob_mp_native_uart_get(mp_obj_t obj) {
    mp_obj_t base = native_base(obj, &ob_mp_native_uart_type);
    if (base == MP_OBJ_NULL) {
        return NULL;
    }
    const ob_mp_native_uart_t *wire = MP_OBJ_TO_PTR(base);
    return wire->uart.write != NULL ? &wire->uart : NULL;
}
