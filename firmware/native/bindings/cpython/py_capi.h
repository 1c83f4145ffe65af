/*
 * The C-API of openbricks_native for other extension modules.
 *
 * The simulator's physics callback (openbricks_sim._mjcontrol) must tick the
 * control cores every millisecond of simulated time without a Python call,
 * and must give Servo/DriveBase objects native wheel IO. Extension modules
 * cannot link against each other's symbols, so openbricks_native publishes
 * what they need in one capsule, the usual CPython pattern:
 *
 *     const ob_py_capi_t *capi = ob_py_capi_import();   // once, at module init
 *     if (capi == NULL) return NULL;                      // ImportError/RuntimeError set
 *     ...
 *     if (capi->motor_process_tick(capi->motor_process, now_ms) < 0) { ... error set ... }
 *
 * Everything here needs the GIL, like any other use of Python objects.
 */
#ifndef OB_PY_CAPI_H
#define OB_PY_CAPI_H

#define PY_SSIZE_T_CLEAN
#include <Python.h>
#include <stdint.h>

#define OB_PY_CAPI_CAPSULE "openbricks_native._C_API"
/* A native byte wire for SerialBus(uart): a capsule of this name holding an ob_uart_t (uart.h). */
#define OB_UART_CAPSULE "openbricks_native.uart"
/* Bumped whenever a member changes meaning; members are only ever appended. */
#define OB_PY_CAPI_VERSION 1u

typedef struct {
    /* OB_PY_CAPI_VERSION of the openbricks_native that filled this in. */
    unsigned int version;
    /* openbricks_native.MotorIO: the base type of native motor IO providers (py_motor_io.h). */
    PyTypeObject *motor_io_type;
    /* openbricks_native.MotorProcess, and the module's motor_process, the one the hub runtime uses
     * (a strong reference held for the life of the module). */
    PyTypeObject *motor_process_type;
    PyObject *motor_process;
    /*
     * process.tick(now_ms) without a Python call frame: advance the clock and
     * tick every subscriber once. Returns 0, or -1 with the first error a
     * subscriber raised (after all of them ran), or a TypeError when process
     * is not a MotorProcess.
     */
    int (*motor_process_tick)(PyObject *process, uint32_t now_ms);
} ob_py_capi_t;

/* Defined in py_scheduler.c; published through the capsule. */
int ob_py_motor_process_tick(PyObject *process, uint32_t now_ms);

/* Import the capsule (imports openbricks_native if needed); NULL with an exception set on failure. */
static inline const ob_py_capi_t *ob_py_capi_import(void) {
    const ob_py_capi_t *capi = (const ob_py_capi_t *)PyCapsule_Import(OB_PY_CAPI_CAPSULE, 0);
    if (capi != NULL && capi->version < OB_PY_CAPI_VERSION) {
        PyErr_Format(PyExc_ImportError,
                     "openbricks_native's C-API is version %u but this module needs %u: rebuild both "
                     "extensions from the same checkout (python setup.py build_ext)",
                     capi->version, OB_PY_CAPI_VERSION);
        return NULL;
    }
    return capi;
}

#endif /* OB_PY_CAPI_H */
