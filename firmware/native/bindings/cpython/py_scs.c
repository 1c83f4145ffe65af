#include "bindings.h"

int ob_py_add_scs(PyObject *module) {
    (void)module;
    return 0;
}
