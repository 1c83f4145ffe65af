#include "bindings.h"

int ob_py_add_imu_yaw(PyObject *module) {
    (void)module;
    return 0;
}
