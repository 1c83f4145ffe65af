/*
 * Observer: the alpha-beta estimator on its own, for tests and for host code
 * that filters an angle it reads itself.
 */
#include <stddef.h>

#include "bindings.h"
#include "observer.h"
#include "py_args.h"

typedef struct {
    PyObject_HEAD
    ob_observer_t ob;
} ObserverObject;

static int gain_arg(PyObject *obj, const char *name, float *out) {
    if (ob_py_float(obj, "Observer", name, out) < 0) {
        return -1;
    }
    if (!(*out > 0.0f && *out <= 1.0f)) {
        PyErr_Format(PyExc_ValueError, "Observer: %s must be within (0, 1], got %R", name, obj);
        return -1;
    }
    return 0;
}

static int observer_init(ObserverObject *self, PyObject *args, PyObject *kwargs) {
    static char *kwlist[] = {"alpha", "beta", "x_deg", NULL};
    PyObject *alpha_obj = NULL, *beta_obj = NULL, *x_obj = NULL;
    if (!PyArg_ParseTupleAndKeywords(args, kwargs, "|OOO:Observer", kwlist, &alpha_obj, &beta_obj, &x_obj)) {
        return -1;
    }
    float alpha = OB_OBSERVER_DEFAULT_ALPHA, beta = OB_OBSERVER_DEFAULT_BETA, x = 0.0f;
    if ((alpha_obj != NULL && gain_arg(alpha_obj, "alpha", &alpha) < 0) ||
        (beta_obj != NULL && gain_arg(beta_obj, "beta", &beta) < 0) ||
        (x_obj != NULL && ob_py_float(x_obj, "Observer", "x_deg", &x) < 0)) {
        return -1;
    }
    ob_observer_init(&self->ob, alpha, beta);
    ob_observer_reset(&self->ob, x);
    return 0;
}

static int dt_arg(PyObject *obj, const char *where, float *dt) {
    if (ob_py_float(obj, where, "dt_s", dt) < 0) {
        return -1;
    }
    if (*dt < 0.0f) {
        PyErr_Format(PyExc_ValueError, "%s: dt_s must be >= 0, got %R", where, obj);
        return -1;
    }
    return 0;
}

static PyObject *observer_update(ObserverObject *self, PyObject *const *args, Py_ssize_t nargs) {
    static const char *where = "Observer.update";
    if (nargs != 2) {
        PyErr_Format(PyExc_TypeError, "%s(measured_deg, dt_s) takes 2 arguments, got %zd", where, nargs);
        return NULL;
    }
    float measured, dt;
    if (ob_py_float(args[0], where, "measured_deg", &measured) < 0 || dt_arg(args[1], where, &dt) < 0) {
        return NULL;
    }
    ob_observer_update(&self->ob, measured, dt);
    return Py_BuildValue("(dd)", (double)self->ob.x_deg, (double)self->ob.v_dps);
}

static PyObject *observer_predict(ObserverObject *self, PyObject *arg) {
    float dt;
    if (dt_arg(arg, "Observer.predict", &dt) < 0) {
        return NULL;
    }
    ob_observer_predict(&self->ob, dt);
    return Py_BuildValue("(dd)", (double)self->ob.x_deg, (double)self->ob.v_dps);
}

static PyObject *observer_reset(ObserverObject *self, PyObject *args, PyObject *kwargs) {
    static char *kwlist[] = {"x_deg", NULL};
    PyObject *x_obj = NULL;
    if (!PyArg_ParseTupleAndKeywords(args, kwargs, "|O:reset", kwlist, &x_obj)) {
        return NULL;
    }
    float x = 0.0f;
    if (x_obj != NULL && ob_py_float(x_obj, "Observer.reset", "x_deg", &x) < 0) {
        return NULL;
    }
    ob_observer_reset(&self->ob, x);
    Py_RETURN_NONE;
}

static PyObject *observer_get(ObserverObject *self, void *closure) {
    const float *field = (const float *)((const char *)&self->ob + (size_t)closure);
    return PyFloat_FromDouble((double)*field);
}

static PyMethodDef observer_methods[] = {
    {"update", (PyCFunction)(void (*)(void))observer_update, METH_FASTCALL,
     "update(measured_deg, dt_s) -> (x_deg, v_dps): predict over dt_s, then correct with the reading."},
    {"predict", (PyCFunction)observer_predict, METH_O,
     "predict(dt_s) -> (x_deg, v_dps): advance with no reading (the sensor was silent)."},
    {"reset", (PyCFunction)(void (*)(void))observer_reset, METH_VARARGS | METH_KEYWORDS,
     "reset(x_deg=0.0): snap to x_deg at rest."},
    {NULL, NULL, 0, NULL},
};

static PyGetSetDef observer_getset[] = {
    {"x_deg", (getter)observer_get, NULL, "Estimated position.", (void *)offsetof(ob_observer_t, x_deg)},
    {"v_dps", (getter)observer_get, NULL, "Estimated speed.", (void *)offsetof(ob_observer_t, v_dps)},
    {"alpha", (getter)observer_get, NULL, "Position correction gain.", (void *)offsetof(ob_observer_t, alpha)},
    {"beta", (getter)observer_get, NULL, "Speed correction gain.", (void *)offsetof(ob_observer_t, beta)},
    {NULL, NULL, NULL, NULL, NULL},
};

static PyTypeObject ObserverType = {
    PyVarObject_HEAD_INIT(NULL, 0)
    .tp_name = "openbricks_native.Observer",
    .tp_basicsize = sizeof(ObserverObject),
    .tp_flags = Py_TPFLAGS_DEFAULT,
    .tp_doc = "Observer(alpha=0.3, beta=0.04, x_deg=0.0)\n\n"
              "Alpha-beta estimator of angle and speed from a quantised angle reading. The default gains suit a "
              "4096-count encoder read at 1 kHz.",
    .tp_new = PyType_GenericNew,
    .tp_init = (initproc)observer_init,
    .tp_methods = observer_methods,
    .tp_getset = observer_getset,
};

int ob_py_add_observer(PyObject *module) {
    if (PyType_Ready(&ObserverType) < 0) {
        return -1;
    }
    Py_INCREF(&ObserverType);
    if (PyModule_AddObject(module, "Observer", (PyObject *)&ObserverType) < 0) {
        Py_DECREF(&ObserverType);
        return -1;
    }
    return 0;
}
