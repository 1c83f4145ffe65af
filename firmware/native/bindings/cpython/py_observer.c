#include "bindings.h"

int ob_py_add_observer(PyObject *module) {
    (void)module;
    return 0;
}
