/*
 * openbricks_native.MotorIO and the module's C-API capsule (py_capi.h).
 *
 * MotorIO on its own does nothing: it is the base type that native IO
 * providers derive from (py_motor_io.h). It is constructible so that tests can
 * check that controllers refuse a provider with no functions.
 */
#include "bindings.h"
#include "py_capi.h"
#include "py_motor_io.h"

PyTypeObject ob_py_motor_io_type = {
    PyVarObject_HEAD_INIT(NULL, 0)
    .tp_name = "openbricks_native.MotorIO",
    .tp_basicsize = sizeof(ob_py_motor_io_t),
    .tp_flags = Py_TPFLAGS_DEFAULT | Py_TPFLAGS_BASETYPE,
    .tp_new = PyType_GenericNew,
    .tp_doc = "Base of native motor IO providers (e.g. the simulator's wheels): a Servo(io=...) or "
              "DriveBase(left_io=..., right_io=...) built on one reads and drives the motor through C "
              "functions, with no Python call per tick.",
};

static ob_py_capi_t capi;

int ob_py_add_capi(PyObject *module) {
    if (PyType_Ready(&ob_py_motor_io_type) < 0) {
        return -1;
    }
    if (PyModule_AddObjectRef(module, "MotorIO", (PyObject *)&ob_py_motor_io_type) < 0) {
        return -1;
    }
    /* The scheduler's adder ran first (module.c orders the adders). */
    PyObject *process_type = PyObject_GetAttrString(module, "MotorProcess");
    if (process_type == NULL) {
        return -1;
    }
    PyObject *process = PyObject_GetAttrString(module, "motor_process");
    if (process == NULL) {
        Py_DECREF(process_type);
        return -1;
    }
    capi.version = OB_PY_CAPI_VERSION;
    capi.motor_io_type = &ob_py_motor_io_type;
    capi.motor_process_type = (PyTypeObject *)process_type; /* the module keeps the type alive */
    Py_DECREF(process_type);
    capi.motor_process = process; /* strong reference, held for the life of the process */
    capi.motor_process_tick = ob_py_motor_process_tick;
    PyObject *capsule = PyCapsule_New(&capi, OB_PY_CAPI_CAPSULE, NULL);
    if (capsule == NULL) {
        return -1;
    }
    if (PyModule_AddObject(module, "_C_API", capsule) < 0) {
        Py_DECREF(capsule);
        return -1;
    }
    return 0;
}
