/*
 * openbricks_native: the control cores of the firmware, compiled for CPython.
 *
 * The simulator installs this module as _openbricks_native so the hub runtime
 * imports the same math it runs on the ESP32.
 */
#include "bindings.h"

static struct PyModuleDef ob_module_def = {
    PyModuleDef_HEAD_INIT,
    "openbricks_native",
    "Control cores of the openbricks firmware (trajectory, observer, servo, drivebase, "
    "scheduler, serial-bus codec and engine, IMU heading, PCNT encoder, ICM-45686, H-bridge), compiled for the host.",
    -1,
    NULL,
};

typedef int (*ob_py_adder_t)(PyObject *);

static const ob_py_adder_t ob_py_adders[] = {
    ob_py_add_trajectory, ob_py_add_observer, ob_py_add_scheduler, ob_py_add_servo,
    ob_py_add_drivebase,  ob_py_add_scs,      ob_py_add_imu_yaw,   ob_py_add_capi, ob_py_add_serial_bus,
    ob_py_add_encoder,   ob_py_add_icm45686, ob_py_add_hbridge,
};

PyMODINIT_FUNC PyInit_openbricks_native(void) {
    PyObject *m = PyModule_Create(&ob_module_def);
    if (m == NULL) {
        return NULL;
    }
    for (size_t i = 0; i < sizeof(ob_py_adders) / sizeof(ob_py_adders[0]); i++) {
        if (ob_py_adders[i](m) < 0) {
            Py_DECREF(m);
            return NULL;
        }
    }
    return m;
}
