/*
 * openbricks_native.HBridge on the host: the H-bridge core (hbridge.h) with no
 * pins wired, keeping the levels it would put on IN1/IN2/EN for levels() to
 * report (MicroPython: mp_hbridge.c, where the hub drives GPIO and LEDC).
 * The host has no LEDC: asking for pins is refused.
 *
 * motor_io(encoder, deg_per_count) is the same MotorIO the hub builds: the
 * encoder core in, this bridge out, joined in C (dc_motor_io.h), so a Servo
 * or DriveBase over it runs with no Python call per tick.
 */
#include "bindings.h"
#include "dc_motor_io.h"
#include "hbridge.h"
#include "py_args.h"
#include "py_motor_io.h"

typedef struct {
    PyObject_HEAD
    ob_hbridge_t hb;
    bool closed;
} HBridgeObject;

typedef struct {
    ob_py_motor_io_t base;
    ob_dc_motor_io_t dc;
    PyObject *bridge;
    PyObject *encoder;
} DCMotorIOObject;

static PyTypeObject HBridgeType;
static PyTypeObject DCMotorIOType;

static int hbridge_init(HBridgeObject *self, PyObject *args, PyObject *kwargs) {
    static char *kwlist[] = {"in1", "in2", "pwm", "invert", "freq_hz", NULL};
    PyObject *in1 = Py_None, *in2 = Py_None, *pwm = Py_None, *freq_obj = NULL;
    int invert = 0;
    if (!PyArg_ParseTupleAndKeywords(args, kwargs, "|OOO$pO:HBridge", kwlist, &in1, &in2, &pwm, &invert,
                                     &freq_obj)) {
        return -1;
    }
    int n_pins = (in1 != Py_None) + (in2 != Py_None) + (pwm != Py_None);
    if (n_pins != 0 && n_pins != 3) {
        PyErr_SetString(PyExc_ValueError, "HBridge(): give all three pins, in1, in2 and pwm, or none");
        return -1;
    }
    if (n_pins != 0) {
        PyErr_SetString(PyExc_OSError, "HBridge: this build has no LEDC peripheral (only the ESP32 firmware drives "
                                        "pins); leave the pins out");
        return -1;
    }
    ob_hbridge_config_t cfg;
    ob_hbridge_default_config(&cfg, OB_HBRIDGE_DEFAULT_FREQ_HZ);
    cfg.invert = invert != 0;
    if (freq_obj != NULL) {
        if (!PyLong_Check(freq_obj) || PyBool_Check(freq_obj)) {
            PyErr_Format(PyExc_TypeError, "HBridge(): freq_hz must be an int, not %.100s", Py_TYPE(freq_obj)->tp_name);
            return -1;
        }
        int overflow = 0;
        long long freq = PyLong_AsLongLongAndOverflow(freq_obj, &overflow);
        if (freq == -1 && PyErr_Occurred()) {
            return -1;
        }
        cfg.freq_hz = overflow != 0 || freq < 0 || freq > (long long)UINT32_MAX ? 0u : (uint32_t)freq;
    }
    ob_hbridge_error_t error = ob_hbridge_init(&self->hb, &cfg, NULL);
    if (error != OB_HBRIDGE_OK) {
        PyErr_Format(PyExc_ValueError, "HBridge(): %s", ob_hbridge_strerror(error));
        return -1;
    }
    self->closed = false;
    return 0;
}

static int check_open(HBridgeObject *self, const char *method) {
    if (self->closed) {
        PyErr_Format(PyExc_ValueError, "HBridge.%s(): the bridge was closed; construct a new one", method);
        return -1;
    }
    return 0;
}

static PyObject *hbridge_drive(HBridgeObject *self, PyObject *arg) {
    float duty;
    if (check_open(self, "drive") < 0 || ob_py_float(arg, "HBridge.drive()", "duty_pct", &duty) < 0) {
        return NULL;
    }
    ob_hbridge_drive(&self->hb, duty);
    Py_RETURN_NONE;
}

static PyObject *hbridge_brake(HBridgeObject *self, PyObject *unused) {
    (void)unused;
    if (check_open(self, "brake") < 0) {
        return NULL;
    }
    ob_hbridge_brake(&self->hb);
    Py_RETURN_NONE;
}

static PyObject *hbridge_coast(HBridgeObject *self, PyObject *unused) {
    (void)unused;
    if (check_open(self, "coast") < 0) {
        return NULL;
    }
    ob_hbridge_coast(&self->hb);
    Py_RETURN_NONE;
}

static PyObject *hbridge_levels(HBridgeObject *self, PyObject *unused) {
    (void)unused;
    const ob_hbridge_levels_t *levels = &self->hb.levels;
    return Py_BuildValue("(NNkk)", PyBool_FromLong(levels->in1), PyBool_FromLong(levels->in2),
                         (unsigned long)levels->duty, (unsigned long)ob_hbridge_duty_max(&self->hb));
}

static PyObject *hbridge_duty(HBridgeObject *self, PyObject *unused) {
    (void)unused;
    return PyFloat_FromDouble(self->hb.duty_pct);
}

static PyObject *hbridge_state(HBridgeObject *self, PyObject *unused) {
    (void)unused;
    return PyUnicode_FromString(ob_hbridge_state_name(self->hb.state));
}

static PyObject *hbridge_stats(HBridgeObject *self, PyObject *unused) {
    (void)unused;
    return Py_BuildValue("(kk)", (unsigned long)self->hb.writes, (unsigned long)self->hb.write_errors);
}

static PyObject *hbridge_motor_io(HBridgeObject *self, PyObject *args) {
    PyObject *encoder_obj, *deg_obj;
    float check;
    if (check_open(self, "motor_io") < 0 || !PyArg_ParseTuple(args, "OO:motor_io", &encoder_obj, &deg_obj)) {
        return NULL;
    }
    ob_encoder_t *encoder = ob_py_pcnt_encoder_get(encoder_obj);
    if (encoder == NULL) {
        PyErr_Format(PyExc_TypeError, "HBridge.motor_io(): encoder must be an open PCNTEncoder, not %.100s",
                     Py_TYPE(encoder_obj)->tp_name);
        return NULL;
    }
    if (ob_py_positive_float(deg_obj, "HBridge.motor_io()", "deg_per_count", &check) < 0) {
        return NULL;
    }
    DCMotorIOObject *io = PyObject_GC_New(DCMotorIOObject, &DCMotorIOType);
    if (io == NULL) {
        return NULL;
    }
    /* Read again in double: a float would round 360 / 68028 in the sixth digit. */
    ob_dc_motor_io_init(&io->dc, encoder, &self->hb, PyFloat_AsDouble(deg_obj));
    io->base.io = ob_dc_motor_io(&io->dc);
    io->bridge = Py_NewRef((PyObject *)self);
    io->encoder = Py_NewRef(encoder_obj);
    PyObject_GC_Track(io);
    return (PyObject *)io;
}

static PyObject *hbridge_close(HBridgeObject *self, PyObject *unused) {
    (void)unused;
    if (!self->closed) {
        ob_hbridge_unwire(&self->hb);
        self->closed = true;
    }
    Py_RETURN_NONE;
}

static PyMethodDef hbridge_methods[] = {
    {"drive", (PyCFunction)hbridge_drive, METH_O,
     "drive(duty_pct)\n\nDrive at duty_pct (-100..100, sign = direction after invert); 0 brakes."},
    {"brake", (PyCFunction)hbridge_brake, METH_NOARGS, "brake()\n\nShort the winding (IN1 = IN2 = 1, EN full)."},
    {"coast", (PyCFunction)hbridge_coast, METH_NOARGS, "coast()\n\nOutputs off (IN1 = IN2 = 0, EN 0)."},
    {"levels", (PyCFunction)hbridge_levels, METH_NOARGS,
     "levels() -> (in1, in2, duty, duty_max)\n\nWhat the pins were last told."},
    {"duty", (PyCFunction)hbridge_duty, METH_NOARGS, "duty() -> float\n\nThe duty driven (user frame, clamped)."},
    {"state", (PyCFunction)hbridge_state, METH_NOARGS,
     "state() -> str\n\nWhat the pins do: 'coast', 'brake', 'forward' or 'reverse' (invert applied)."},
    {"stats", (PyCFunction)hbridge_stats, METH_NOARGS,
     "stats() -> (writes, write_errors)\n\nLevel changes written to the pins, and writes they refused."},
    {"motor_io", (PyCFunction)hbridge_motor_io, METH_VARARGS,
     "motor_io(encoder, deg_per_count) -> MotorIO\n\nThe encoder core in, this bridge out, for Servo(io=) or "
     "DriveBase(left_io=, right_io=)."},
    {"close", (PyCFunction)hbridge_close, METH_NOARGS, "close()\n\nCoast and let go of the pins."},
    {NULL, NULL, 0, NULL},
};

static PyTypeObject HBridgeType = {
    PyVarObject_HEAD_INIT(NULL, 0)
    .tp_name = "openbricks_native.HBridge",
    .tp_basicsize = sizeof(HBridgeObject),
    .tp_flags = Py_TPFLAGS_DEFAULT,
    .tp_new = PyType_GenericNew,
    .tp_init = (initproc)hbridge_init,
    .tp_methods = hbridge_methods,
    .tp_doc = "HBridge(in1=None, in2=None, pwm=None, *, invert=False, freq_hz=1000)\n\nOne H-bridge channel "
              "(L298N, TB6612) driven from a signed duty (H-bridge core).",
};

/* ---- A DC motor's IO ---- */

static int dio_traverse(DCMotorIOObject *self, visitproc visit, void *arg) {
    Py_VISIT(self->bridge);
    Py_VISIT(self->encoder);
    return 0;
}

static int dio_clear(DCMotorIOObject *self) {
    Py_CLEAR(self->bridge);
    Py_CLEAR(self->encoder);
    return 0;
}

static void dio_dealloc(DCMotorIOObject *self) {
    PyObject_GC_UnTrack(self);
    dio_clear(self);
    Py_TYPE(self)->tp_free((PyObject *)self);
}

static PyObject *dio_read_angle(DCMotorIOObject *self, PyObject *unused) {
    (void)unused;
    float angle;
    if (self->bridge == NULL || !self->base.io.read_angle(self->base.io.ctx, &angle)) {
        Py_RETURN_NONE;
    }
    return PyFloat_FromDouble(angle);
}

static PyObject *dio_write_duty(DCMotorIOObject *self, PyObject *arg) {
    float duty;
    if (ob_py_float(arg, "write_duty", "duty_pct", &duty) < 0) {
        return NULL;
    }
    self->base.io.write_duty(self->base.io.ctx, duty);
    Py_RETURN_NONE;
}

static PyObject *dio_coast(DCMotorIOObject *self, PyObject *unused) {
    (void)unused;
    self->base.io.write_coast(self->base.io.ctx);
    Py_RETURN_NONE;
}

static PyMethodDef dio_methods[] = {
    {"read_angle", (PyCFunction)dio_read_angle, METH_NOARGS, "The output shaft's angle in degrees, or None."},
    {"write_duty", (PyCFunction)dio_write_duty, METH_O, "write_duty(duty_pct): drive the bridge; 0 brakes."},
    {"coast", (PyCFunction)dio_coast, METH_NOARGS, "Switch the bridge's outputs off."},
    {NULL, NULL, 0, NULL},
};

static PyTypeObject DCMotorIOType = {
    PyVarObject_HEAD_INIT(NULL, 0)
    .tp_name = "openbricks_native.HBridgeMotorIO",
    .tp_basicsize = sizeof(DCMotorIOObject),
    .tp_flags = Py_TPFLAGS_DEFAULT | Py_TPFLAGS_HAVE_GC,
    .tp_dealloc = (destructor)dio_dealloc,
    .tp_traverse = (traverseproc)dio_traverse,
    .tp_clear = (inquiry)dio_clear,
    .tp_methods = dio_methods,
    .tp_doc = "A DC motor's IO: a PCNTEncoder's count in, an HBridge out.",
};

int ob_py_add_hbridge(PyObject *module) {
    DCMotorIOType.tp_base = &ob_py_motor_io_type;
    if (PyType_Ready(&ob_py_motor_io_type) < 0 || PyType_Ready(&HBridgeType) < 0 ||
        PyType_Ready(&DCMotorIOType) < 0) {
        return -1;
    }
    /* The host drives no pins: the runtime keeps machine.Pin/PWM (the simulator's) on builds like this. */
    if (PyDict_SetItemString(HBridgeType.tp_dict, "HARDWARE", Py_False) < 0) {
        return -1;
    }
    PyType_Modified(&HBridgeType);
    return PyModule_AddObjectRef(module, "HBridge", (PyObject *)&HBridgeType);
}
