/* The simulator's Python-time charge, as a C profile function (extension openbricks_pycost).
 *
 * sim/python_cost.py charges every call the program and the hub runtime make a few simulated
 * microseconds, so a program that spins without sleeping still lets time pass. A Python-level
 * profile function would cost more host time than the whole control path; this one costs a
 * read of a slot on the code object per call (CPython's co_extra: a dictionary keyed by code
 * objects hashed each code object's fields on every call, half the charge's cost). The policy
 * (which code counts, what to do with the time) stays in Python: `classify(filename) -> bool` is
 * asked once per code object, and `charge(us)` is called each time `batch_us` have been counted.
 */
#define PY_SSIZE_T_CLEAN
#include <Python.h>
#include <frameobject.h>

#if PY_VERSION_HEX >= 0x030C0000
#define CODE_GET_EXTRA PyUnstable_Code_GetExtra
#define CODE_SET_EXTRA PyUnstable_Code_SetExtra
#define REQUEST_CODE_EXTRA_INDEX PyUnstable_Eval_RequestCodeExtraIndex
#else
#define CODE_GET_EXTRA _PyCode_GetExtra
#define CODE_SET_EXTRA _PyCode_SetExtra
#define REQUEST_CODE_EXTRA_INDEX _PyEval_RequestCodeExtraIndex
#endif

/* The verdict kept in each code object's extra slot: not asked yet (NULL), counts, free. */
#define VERDICT_COUNTS ((void *)1)
#define VERDICT_FREE ((void *)2)

static Py_ssize_t extra_index = -1; /* this module's co_extra slot, one per process */
static long classify_epoch = 0;     /* verdicts belong to one Cost object's classify */

typedef struct {
    PyObject_HEAD
    PyObject *classify; /* callable(filename) -> bool */
    PyObject *charge;   /* callable(us) */
    long epoch;         /* this object's classify_epoch */
    long call_us;
    long batch_us;
    long pending_us;
} CostObject;

static int cost_profile(PyObject *self_obj, PyFrameObject *frame, int what, PyObject *arg) {
    (void)arg;
    if (what != PyTrace_CALL && what != PyTrace_C_CALL) {
        return 0;
    }
    CostObject *self = (CostObject *)self_obj;
    PyCodeObject *code = PyFrame_GetCode(frame);
    void *extra = NULL;
    if (CODE_GET_EXTRA((PyObject *)code, extra_index, &extra) < 0) {
        Py_DECREF(code);
        return -1;
    }
    /* A slot holds (epoch << 2) | verdict, so another Cost's classify asks afresh. */
    uintptr_t slot = (uintptr_t)extra;
    void *verdict = ((long)(slot >> 2) == self->epoch) ? (void *)(slot & 3) : NULL;
    if (verdict == NULL) {
        PyObject *answer = PyObject_CallOneArg(self->classify, code->co_filename);
        int counts = answer == NULL ? -1 : PyObject_IsTrue(answer);
        Py_XDECREF(answer);
        if (counts < 0) {
            Py_DECREF(code);
            return -1;
        }
        verdict = counts ? VERDICT_COUNTS : VERDICT_FREE;
        uintptr_t stored = ((uintptr_t)self->epoch << 2) | (uintptr_t)verdict;
        if (CODE_SET_EXTRA((PyObject *)code, extra_index, (void *)stored) < 0) {
            Py_DECREF(code);
            return -1;
        }
    }
    Py_DECREF(code);
    if (verdict != VERDICT_COUNTS) {
        return 0;
    }
    self->pending_us += self->call_us;
    if (self->pending_us < self->batch_us) {
        return 0;
    }
    long due_us = self->pending_us;
    self->pending_us = 0;
    PyObject *result = PyObject_CallFunction(self->charge, "l", due_us);
    if (result == NULL) {
        return -1; /* SimTimeLimit, a stop: raised into the program at this call */
    }
    Py_DECREF(result);
    return 0;
}

static int cost_init(CostObject *self, PyObject *args, PyObject *kwargs) {
    static char *kwlist[] = {"classify", "charge", "call_us", "batch_us", NULL};
    PyObject *classify, *charge;
    long call_us, batch_us;
    if (!PyArg_ParseTupleAndKeywords(args, kwargs, "OOll", kwlist, &classify, &charge, &call_us, &batch_us)) {
        return -1;
    }
    if (!PyCallable_Check(classify) || !PyCallable_Check(charge) || call_us < 0 || batch_us < 1) {
        PyErr_SetString(PyExc_ValueError, "Cost(classify, charge, call_us >= 0, batch_us >= 1)");
        return -1;
    }
    Py_XSETREF(self->classify, Py_NewRef(classify));
    Py_XSETREF(self->charge, Py_NewRef(charge));
    self->epoch = ++classify_epoch;
    self->call_us = call_us;
    self->batch_us = batch_us;
    self->pending_us = 0;
    return 0;
}

static PyObject *cost_install(CostObject *self, PyObject *unused) {
    (void)unused;
    PyEval_SetProfile(cost_profile, (PyObject *)self);
    Py_RETURN_NONE;
}

/* While the clock advances (a sleep, a charge), the simulator's own code runs: it never counts, and
 * with no profile function set CPython runs it at full speed. The caller keeps the nesting (clock.py). */
static int counting(CostObject *self) {
    PyThreadState *tstate = PyThreadState_Get();
    return tstate->c_profilefunc == cost_profile && tstate->c_profileobj == (PyObject *)self;
}

static PyObject *cost_pause(CostObject *self, PyObject *unused) {
    (void)unused;
    if (counting(self)) {
        PyEval_SetProfile(NULL, NULL);
    }
    Py_RETURN_NONE;
}

static PyObject *cost_get_counting(CostObject *self, void *closure) {
    (void)closure;
    return PyBool_FromLong(counting(self));
}

static PyObject *cost_uninstall(CostObject *self, PyObject *unused) {
    (void)self;
    (void)unused;
    PyEval_SetProfile(NULL, NULL);
    Py_RETURN_NONE;
}

static int cost_traverse(CostObject *self, visitproc visit, void *arg) {
    Py_VISIT(self->classify);
    Py_VISIT(self->charge);
    return 0;
}

static int cost_clear(CostObject *self) {
    Py_CLEAR(self->classify);
    Py_CLEAR(self->charge);
    return 0;
}

static void cost_dealloc(CostObject *self) {
    PyObject_GC_UnTrack(self);
    cost_clear(self);
    Py_TYPE(self)->tp_free((PyObject *)self);
}

static PyObject *cost_get_pending(CostObject *self, void *closure) {
    (void)closure;
    return PyLong_FromLong(self->pending_us);
}

static PyMethodDef cost_methods[] = {
    {"install", (PyCFunction)cost_install, METH_NOARGS, "Profile the calling thread from now on."},
    {"uninstall", (PyCFunction)cost_uninstall, METH_NOARGS, "Stop profiling the calling thread."},
    {"pause", (PyCFunction)cost_pause, METH_NOARGS, "Stop counting in this thread until resume()."},
    {"resume", (PyCFunction)cost_install, METH_NOARGS, "Count again after pause() (install() again)."},
    {NULL, NULL, 0, NULL},
};

static PyGetSetDef cost_getset[] = {
    {"pending_us", (getter)cost_get_pending, NULL, "Counted microseconds not yet charged.", NULL},
    {"counting", (getter)cost_get_counting, NULL, "Whether this thread's calls are counted now.", NULL},
    {NULL, NULL, NULL, NULL, NULL},
};

static PyTypeObject CostType = {
    PyVarObject_HEAD_INIT(NULL, 0).tp_name = "openbricks_pycost.Cost",
    .tp_basicsize = sizeof(CostObject),
    .tp_flags = Py_TPFLAGS_DEFAULT | Py_TPFLAGS_HAVE_GC,
    .tp_doc = "Cost(classify, charge, call_us, batch_us): a profile function charging Python calls.",
    .tp_new = PyType_GenericNew,
    .tp_init = (initproc)cost_init,
    .tp_dealloc = (destructor)cost_dealloc,
    .tp_traverse = (traverseproc)cost_traverse,
    .tp_clear = (inquiry)cost_clear,
    .tp_methods = cost_methods,
    .tp_getset = cost_getset,
};

static struct PyModuleDef module_def = {
    PyModuleDef_HEAD_INIT, "openbricks_pycost", "The simulator's Python-time charge (sim/python_cost.py).", -1,
    NULL, NULL, NULL, NULL, NULL,
};

PyMODINIT_FUNC PyInit_openbricks_pycost(void) {
    if (PyType_Ready(&CostType) < 0) {
        return NULL;
    }
    if (extra_index < 0) {
        extra_index = REQUEST_CODE_EXTRA_INDEX(NULL); /* the slot holds plain numbers: nothing to free */
        if (extra_index < 0) {
            PyErr_SetString(PyExc_RuntimeError, "openbricks_pycost: no code object extra slot left");
            return NULL;
        }
    }
    PyObject *module = PyModule_Create(&module_def);
    if (module == NULL) {
        return NULL;
    }
    if (PyModule_AddObjectRef(module, "Cost", (PyObject *)&CostType) < 0) {
        Py_DECREF(module);
        return NULL;
    }
    return module;
}
