#include "bindings.h"

int ob_py_add_servo(PyObject *module) {
    (void)module;
    return 0;
}
