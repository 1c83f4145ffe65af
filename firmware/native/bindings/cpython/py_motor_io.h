/*
 * Native motor IO: how a binding object hands an ob_motor_io_t to a
 * controller without any Python call per tick.
 *
 * A Servo or DriveBase built with Python callables crosses into Python three
 * times per control period. The simulator (and any other host that owns its
 * wheels in C) instead passes objects whose type derives from
 * openbricks_native.MotorIO: their object layout starts with
 * ob_py_motor_io_t, so the controller copies the ob_motor_io_t out of the
 * object and calls the provider's C functions directly.
 *
 *     typedef struct {
 *         ob_py_motor_io_t base;   // first member: PyObject_HEAD + io
 *         ...                      // the provider's own state
 *     } WheelIOObject;
 *
 *     // when building the type, before PyType_Ready:
 *     WheelIOType.tp_base = capi->motor_io_type;   // see py_capi.h
 *
 *     // in tp_init (io.ctx usually points into the object itself):
 *     self->base.io = (ob_motor_io_t){wheel_read_angle, wheel_write_duty, wheel_write_coast, self};
 *
 * Rules for a provider:
 *   - The functions never call Python and never set a Python error: they run
 *     inside motor_process ticks, possibly from a physics step callback.
 *   - io must be fully set once the object is initialised and must not change
 *     afterwards; a consumer copies it when it is constructed.
 *   - A base MotorIO that no provider initialised has all-NULL functions;
 *     consumers refuse it (ob_py_motor_io_ready).
 *
 * Rules for a consumer (Servo(io=...), DriveBase(left_io=..., right_io=...)):
 *   - Keep a strong reference to the provider object for as long as the core
 *     may call its functions (io.ctx points into it), and visit it in
 *     tp_traverse.
 *
 * The type object lives in openbricks_native (py_capi.c). Another extension
 * module cannot link against its symbol, so it finds the type through the
 * module's C-API capsule (py_capi.h).
 */
#ifndef OB_PY_MOTOR_IO_H
#define OB_PY_MOTOR_IO_H

#define PY_SSIZE_T_CLEAN
#include <Python.h>

#include "ob_types.h"

typedef struct {
    PyObject_HEAD
    ob_motor_io_t io;
} ob_py_motor_io_t;

/* The base type, openbricks_native.MotorIO (defined and readied by py_capi.c inside openbricks_native). */
extern PyTypeObject ob_py_motor_io_type;

/* True when obj is a native motor IO provider (any type derived from MotorIO). */
static inline int ob_py_motor_io_check(PyObject *obj) {
    return PyObject_TypeCheck(obj, &ob_py_motor_io_type);
}

/* True when a provider filled in every function of its io. */
static inline int ob_py_motor_io_ready(PyObject *obj) {
    const ob_motor_io_t *io = &((ob_py_motor_io_t *)obj)->io;
    return io->read_angle != NULL && io->write_duty != NULL && io->write_coast != NULL;
}

#endif /* OB_PY_MOTOR_IO_H */
