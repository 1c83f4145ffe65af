#include "bindings.h"

int ob_py_add_scheduler(PyObject *module) {
    (void)module;
    return 0;
}
