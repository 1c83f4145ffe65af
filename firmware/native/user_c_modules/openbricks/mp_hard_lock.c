/*
 * Methods called under the motor lock (hard_timer.h).
 *
 * The hard tick runs the controllers from the timer's own context (another
 * thread on the unix port, the esp_timer task on the hub) while the
 * interpreter keeps running. Every method of the types it may tick
 * (MotorProcess, DriveBase, Servo, SerialBus) is therefore loaded through
 * their attr slot as a bound method that holds the motor lock for the call,
 * so a command is never half applied when the tick reads it; the timer skips
 * a period rather than wait. The lock is recursive: a locked call that runs
 * Python (an IO callable) may reach another locked call.
 */
#include "hard_timer.h"
#include "mp_bindings.h"

typedef struct {
    mp_obj_base_t base;
    mp_obj_t fun;
    mp_obj_t self;
} locked_method_t;

static mp_obj_t locked_method_call(mp_obj_t self_in, size_t n_args, size_t n_kw, const mp_obj_t *args) {
    locked_method_t *method = MP_OBJ_TO_PTR(self_in);
    ob_hard_timer_lock();
    nlr_buf_t nlr;
    if (nlr_push(&nlr) == 0) {
        mp_obj_t result = mp_call_method_self_n_kw(method->fun, method->self, n_args, n_kw, args);
        nlr_pop();
        ob_hard_timer_unlock();
        return result;
    }
    ob_hard_timer_unlock();
    nlr_jump(nlr.ret_val);
}

static MP_DEFINE_CONST_OBJ_TYPE(
    locked_method_type,
    MP_QSTR_bound_method,
    MP_TYPE_FLAG_NONE,
    call, locked_method_call
    );

void ob_mp_locked_attr(mp_obj_t self_in, qstr attr, mp_obj_t *dest, const mp_obj_dict_t *locals_dict) {
    if (dest[0] != MP_OBJ_NULL) {
        return; /* stores and deletes: read-only */
    }
    if (attr == MP_QSTR___del__) {
        /* The GC runs finalisers while the heap is locked, so no bound method can be allocated
         * here; a finaliser takes the motor lock itself. */
        dest[1] = MP_OBJ_SENTINEL;
        return;
    }
    mp_map_elem_t *elem = mp_map_lookup((mp_map_t *)&locals_dict->map, MP_OBJ_NEW_QSTR(attr), MP_MAP_LOOKUP);
    if (elem == NULL || !mp_obj_is_fun(elem->value)) {
        dest[1] = MP_OBJ_SENTINEL; /* not a method: the usual lookup */
        return;
    }
    locked_method_t *method = mp_obj_malloc(locked_method_t, &locked_method_type);
    method->fun = elem->value;
    method->self = self_in;
    dest[0] = MP_OBJ_FROM_PTR(method);
}
