/*
 * openbricks_native.PCNTEncoder on the host: the encoder core (encoder.h)
 * fed through sample(raw) with what a PCNT unit's counter would read, as the
 * hub's hard tick feeds it from the peripheral (MicroPython: mp_encoder.c).
 * The host has no PCNT: asking for pins is refused.
 */
#include "bindings.h"
#include "encoder.h"

typedef struct {
    PyObject_HEAD
    ob_encoder_t enc;
    bool closed;
} PCNTEncoderObject;

/* An int (not a bool) that fits int32, or -1 with a TypeError/ValueError naming it. */
static int int32_arg(PyObject *obj, const char *where, const char *name, int32_t *out) {
    if (!PyLong_Check(obj) || PyBool_Check(obj)) {
        PyErr_Format(PyExc_TypeError, "%s: %s must be an int, not %.100s", where, name, Py_TYPE(obj)->tp_name);
        return -1;
    }
    int overflow = 0;
    long long value = PyLong_AsLongLongAndOverflow(obj, &overflow);
    if (value == -1 && PyErr_Occurred()) {
        return -1;
    }
    if (overflow != 0 || value < INT32_MIN || value > INT32_MAX) {
        PyErr_Format(PyExc_ValueError, "%s: %s=%R is out of range (a 32-bit count)", where, name, obj);
        return -1;
    }
    *out = (int32_t)value;
    return 0;
}

static int pcnt_encoder_init(PyObject *self_in, PyObject *args, PyObject *kwargs) {
    static char *kwlist[] = {"counts_per_rev", "invert", "modulus", "pin_a", "pin_b", "unit", "filter", NULL};
    PyObject *cpr_obj, *modulus_obj = NULL, *pin_a = Py_None, *pin_b = Py_None, *unit = NULL, *filter = NULL;
    int invert = 0;
    if (!PyArg_ParseTupleAndKeywords(args, kwargs, "O|$pOOOOO:PCNTEncoder", kwlist, &cpr_obj, &invert,
                                     &modulus_obj, &pin_a, &pin_b, &unit, &filter)) {
        return -1;
    }
    (void)unit;
    (void)filter;
    if (pin_a != Py_None || pin_b != Py_None) {
        PyErr_SetString(PyExc_OSError, "PCNTEncoder: this build has no PCNT peripheral (only the ESP32 firmware "
                                        "counts pins); feed the counter's readings with sample(raw)");
        return -1;
    }
    ob_encoder_config_t cfg;
    ob_encoder_default_config(&cfg, 0);
    if (int32_arg(cpr_obj, "PCNTEncoder()", "counts_per_rev", &cfg.counts_per_rev) < 0 ||
        (modulus_obj != NULL && int32_arg(modulus_obj, "PCNTEncoder()", "modulus", &cfg.modulus) < 0)) {
        return -1;
    }
    cfg.invert = invert != 0;
    PCNTEncoderObject *self = (PCNTEncoderObject *)self_in;
    ob_encoder_error_t error = ob_encoder_init(&self->enc, &cfg, NULL);
    if (error != OB_ENCODER_OK) {
        PyErr_Format(PyExc_ValueError, "PCNTEncoder(): %s", ob_encoder_strerror(error));
        return -1;
    }
    self->closed = false;
    return 0;
}

static int check_open(PCNTEncoderObject *self, const char *method) {
    if (self->closed) {
        PyErr_Format(PyExc_ValueError, "PCNTEncoder.%s(): the encoder was closed; construct a new one", method);
        return -1;
    }
    return 0;
}

static PyObject *pcnt_encoder_sample(PyObject *self_in, PyObject *raw_obj) {
    PCNTEncoderObject *self = (PCNTEncoderObject *)self_in;
    int32_t raw;
    if (check_open(self, "sample") < 0 || int32_arg(raw_obj, "PCNTEncoder.sample()", "raw", &raw) < 0) {
        return NULL;
    }
    ob_encoder_sample(&self->enc, raw);
    Py_RETURN_NONE;
}

static PyObject *pcnt_encoder_count(PyObject *self_in, PyObject *unused) {
    (void)unused;
    PCNTEncoderObject *self = (PCNTEncoderObject *)self_in;
    if (check_open(self, "count") < 0) {
        return NULL;
    }
    return PyLong_FromLongLong((long long)ob_encoder_count(&self->enc));
}

static PyObject *pcnt_encoder_reset(PyObject *self_in, PyObject *args) {
    PCNTEncoderObject *self = (PCNTEncoderObject *)self_in;
    long long count = 0;
    if (check_open(self, "reset") < 0 || !PyArg_ParseTuple(args, "|L:reset", &count)) {
        return NULL;
    }
    ob_encoder_reset_count(&self->enc, (int64_t)count);
    Py_RETURN_NONE;
}

static PyObject *pcnt_encoder_angle(PyObject *self_in, PyObject *unused) {
    (void)unused;
    PCNTEncoderObject *self = (PCNTEncoderObject *)self_in;
    if (check_open(self, "angle") < 0) {
        return NULL;
    }
    return PyFloat_FromDouble(ob_encoder_angle_deg(&self->enc));
}

static PyObject *pcnt_encoder_direction(PyObject *self_in, PyObject *unused) {
    (void)unused;
    return PyLong_FromLong(ob_encoder_direction(&((PCNTEncoderObject *)self_in)->enc));
}

static PyObject *pcnt_encoder_max_step(PyObject *self_in, PyObject *unused) {
    (void)unused;
    return PyLong_FromLong(ob_encoder_max_step(&((PCNTEncoderObject *)self_in)->enc));
}

static PyObject *pcnt_encoder_close(PyObject *self_in, PyObject *unused) {
    (void)unused;
    ((PCNTEncoderObject *)self_in)->closed = true;
    Py_RETURN_NONE;
}

static PyMethodDef pcnt_encoder_methods[] = {
    {"sample", pcnt_encoder_sample, METH_O,
     "sample(raw)\n\nOne reading of the hardware counter (on the hub the hard tick reads the PCNT unit "
     "every millisecond). The first one only sets where counting starts."},
    {"count", pcnt_encoder_count, METH_NOARGS, "count() -> int\n\nPosition in counts since the last reset."},
    {"reset", pcnt_encoder_reset, METH_VARARGS, "reset(count=0)\n\nMake the current position read `count`."},
    {"angle", pcnt_encoder_angle, METH_NOARGS, "angle() -> float\n\nPosition in output-shaft degrees."},
    {"direction", pcnt_encoder_direction, METH_NOARGS,
     "direction() -> int\n\n+1 / -1: the direction of the last movement; 0 when the last sample saw none."},
    {"max_step", pcnt_encoder_max_step, METH_NOARGS,
     "max_step() -> int\n\nCounts the shaft may move between two samples and still be counted right."},
    {"close", pcnt_encoder_close, METH_NOARGS, "close()\n\nStop counting (the hub frees the PCNT unit)."},
    {NULL, NULL, 0, NULL},
};

static PyType_Slot pcnt_encoder_slots[] = {
    {Py_tp_doc, "PCNTEncoder(counts_per_rev, *, invert=False, modulus=32767, pin_a=None, pin_b=None, unit=0, "
                "filter=1023)\n\nA quadrature encoder counted by a wrapping PCNT counter (encoder core)."},
    {Py_tp_init, pcnt_encoder_init},
    {Py_tp_new, PyType_GenericNew},
    {Py_tp_methods, pcnt_encoder_methods},
    {0, NULL},
};

static PyType_Spec pcnt_encoder_spec = {
    "openbricks_native.PCNTEncoder",
    sizeof(PCNTEncoderObject),
    0,
    Py_TPFLAGS_DEFAULT,
    pcnt_encoder_slots,
};

/* The type as created (a heap type), for ob_py_pcnt_encoder_get. */
static PyObject *pcnt_encoder_type;

ob_encoder_t *ob_py_pcnt_encoder_get(PyObject *obj) {
    if (pcnt_encoder_type == NULL || !PyObject_TypeCheck(obj, (PyTypeObject *)pcnt_encoder_type)) {
        return NULL;
    }
    PCNTEncoderObject *self = (PCNTEncoderObject *)obj;
    return self->closed ? NULL : &self->enc;
}

int ob_py_add_encoder(PyObject *module) {
    PyObject *type = PyType_FromSpec(&pcnt_encoder_spec);
    if (type == NULL) {
        return -1;
    }
    pcnt_encoder_type = type; /* the module's reference below keeps it alive */
    /* The host counts no pins: the runtime keeps machine.Encoder (the simulator's) on builds like this. */
    int rc = PyObject_SetAttrString(type, "HARDWARE", Py_False);
    if (rc == 0) {
        rc = PyModule_AddObjectRef(module, "PCNTEncoder", type);
    }
    Py_DECREF(type);
    return rc;
}
