/*
 * How a binding object becomes a native subscriber of motor_process.
 *
 * motor_process ticks its subscribers through the scheduler core, which only
 * knows (ob_tick_fn_t, ctx) pairs. So that motor_process.subscribe(obj) can
 * take a Servo, a DriveBase or any later controller without knowing its type,
 * every such type derives from one small base type, Subscriber, whose object
 * layout is ob_py_subscriber_t. motor_process reads tick_fn/tick_ctx from it
 * and dispatches natively: no Python call per tick.
 *
 * To make a binding type subscribable (DriveBase does exactly this):
 *
 *     typedef struct {
 *         ob_py_subscriber_t base;   // first member: PyObject_HEAD + tick_fn + tick_ctx
 *         ob_drivebase_t db;
 *         ...
 *     } DriveBaseObject;
 *
 *     // in ob_py_add_drivebase(), before PyType_Ready(&DriveBaseType):
 *     DriveBaseType.tp_base = &ob_py_subscriber_type;
 *
 *     // in tp_init, once the core is ready to be ticked:
 *     self->base.tick_fn = ob_drivebase_tick;   // or a binding-level wrapper, see below
 *     self->base.tick_ctx = &self->db;
 *
 * Leave tick_fn NULL for an object that cannot be ticked by the scheduler
 * (e.g. one driven only through its update() fast path, with no IO callables):
 * motor_process.subscribe() then refuses it with a ValueError naming the type.
 * tick_fn/tick_ctx must not change while the object is subscribed; motor_process
 * holds a strong reference to each subscriber, so tick_ctx stays valid.
 *
 * Python errors: a tick_fn may call into Python (e.g. IO callables). It must
 * not call Python while an exception is set, and it may return with one set;
 * motor_process.tick() clears it before the next subscriber runs, finishes the
 * round (the other motors keep being controlled) and then raises the first
 * error. A binding wrapper that stashes the callables' exceptions during the
 * core's tick and restores one at the end is the usual shape (see py_servo.c).
 *
 * ob_py_subscriber_type is defined in py_scheduler.c and is readied by
 * ob_py_add_scheduler(), which module.c calls before the servo and drivebase
 * adders; PyType_Ready on a derived type readies it anyway.
 */
#ifndef OB_PY_SUBSCRIBER_H
#define OB_PY_SUBSCRIBER_H

#include "bindings.h"
#include "scheduler.h"

typedef struct {
    PyObject_HEAD
    ob_tick_fn_t tick_fn; /* called once per motor_process tick; NULL = not subscribable */
    void *tick_ctx;       /* passed to tick_fn */
} ob_py_subscriber_t;

extern PyTypeObject ob_py_subscriber_type;

/* True when obj is a Subscriber (any derived binding type). */
static inline int ob_py_subscriber_check(PyObject *obj) {
    return PyObject_TypeCheck(obj, &ob_py_subscriber_type);
}

#endif /* OB_PY_SUBSCRIBER_H */
