#include "bindings.h"

int ob_py_add_trajectory(PyObject *module) {
    (void)module;
    return 0;
}
