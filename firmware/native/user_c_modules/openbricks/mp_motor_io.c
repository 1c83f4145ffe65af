/*
 * MotorIO and the native UART, counter, SPI and H-bridge pin bases: how a binding object
 * hands a controller, the serial-bus engine or a sensor core C functions that
 * never call Python (host: the MotorIO of py_capi.c / py_motor_io.h).
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

/* The provider part of obj when it derives from `base`, or NULL. */
static void *provider_part(mp_obj_t obj, const mp_obj_type_t *base) {
    mp_obj_t part = native_base(obj, base);
    return part == MP_OBJ_NULL ? NULL : MP_OBJ_TO_PTR(part);
}

MP_DEFINE_CONST_OBJ_TYPE(
    ob_mp_motor_io_type,
    MP_QSTR_MotorIO,
    MP_TYPE_FLAG_NONE
    );

bool ob_mp_motor_io_get(mp_obj_t obj, ob_motor_io_t *io) {
    const ob_mp_motor_io_t *motor = provider_part(obj, &ob_mp_motor_io_type);
    if (motor == NULL || motor->io.read_angle == NULL || motor->io.write_duty == NULL ||
        motor->io.write_coast == NULL) {
        return false;
    }
    *io = motor->io;
    return true;
}

MP_DEFINE_CONST_OBJ_TYPE(
    ob_mp_native_uart_type,
    MP_QSTR_NativeUART,
    MP_TYPE_FLAG_NONE
    );

const ob_uart_t *ob_mp_native_uart_get(mp_obj_t obj) {
    const ob_mp_native_uart_t *wire = provider_part(obj, &ob_mp_native_uart_type);
    return wire != NULL && wire->uart.write != NULL ? &wire->uart : NULL;
}

MP_DEFINE_CONST_OBJ_TYPE(
    ob_mp_native_counter_type,
    MP_QSTR_NativeCounter,
    MP_TYPE_FLAG_NONE
    );

const ob_pcnt_t *ob_mp_native_counter_get(mp_obj_t obj) {
    const ob_mp_native_counter_t *counter = provider_part(obj, &ob_mp_native_counter_type);
    return counter != NULL && counter->pcnt.read != NULL ? &counter->pcnt : NULL;
}

MP_DEFINE_CONST_OBJ_TYPE(
    ob_mp_native_spi_type,
    MP_QSTR_NativeSPI,
    MP_TYPE_FLAG_NONE
    );

const ob_spi_t *ob_mp_native_spi_get(mp_obj_t obj) {
    const ob_mp_native_spi_t *link = provider_part(obj, &ob_mp_native_spi_type);
    return link != NULL && link->spi.transfer != NULL ? &link->spi : NULL;
}

MP_DEFINE_CONST_OBJ_TYPE(
    ob_mp_native_hbridge_pins_type,
    MP_QSTR_NativeHBridgePins,
    MP_TYPE_FLAG_NONE
    );

const ob_hbridge_pins_t *ob_mp_native_hbridge_pins_get(mp_obj_t obj) {
    const ob_mp_native_hbridge_pins_t *pins = provider_part(obj, &ob_mp_native_hbridge_pins_type);
    return pins != NULL && pins->pins.write != NULL ? &pins->pins : NULL;
}
