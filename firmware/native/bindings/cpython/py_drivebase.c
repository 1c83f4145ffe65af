#include "bindings.h"

int ob_py_add_drivebase(PyObject *module) {
    (void)module;
    return 0;
}
