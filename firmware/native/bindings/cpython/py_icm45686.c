/*
 * openbricks_native.ICM45686 on the host: the ICM-45686 core (icm45686.h)
 * talking through a Python transfer(bytes) -> bytes, in front of a register
 * model of the chip (MicroPython: mp_icm45686.c, where the hub's SPI is
 * native and the hard tick samples it). A DriveBase given this object as
 * heading= reads the heading in C, with no Python call per tick.
 */
#include <math.h>
#include <string.h>

#include "bindings.h"
#include "icm45686.h"

typedef struct {
    PyObject_HEAD
    ob_icm45686_t imu;
    PyObject *transfer;
    PyObject *delay_ms;
    /* First exception of a transfer or delay callable since the binding last raised. */
    PyObject *error_type, *error_value, *error_tb;
} ICM45686Object;

static PyTypeObject *icm45686_type;

static void stash(ICM45686Object *self) {
    if (self->error_type == NULL) {
        PyErr_Fetch(&self->error_type, &self->error_value, &self->error_tb);
    } else {
        PyErr_WriteUnraisable((PyObject *)self);
    }
}

static int raise_stashed(ICM45686Object *self) {
    if (self->error_type == NULL) {
        return 0;
    }
    PyErr_Restore(self->error_type, self->error_value, self->error_tb);
    self->error_type = self->error_value = self->error_tb = NULL;
    return -1;
}

static bool py_transfer(void *ctx, const uint8_t *tx, uint8_t *rx, size_t n) {
    ICM45686Object *self = ctx;
    PyObject *result = PyObject_CallFunction(self->transfer, "y#", (const char *)tx, (Py_ssize_t)n);
    if (result == NULL) {
        stash(self);
        return false;
    }
    Py_buffer view;
    if (PyObject_GetBuffer(result, &view, PyBUF_SIMPLE) < 0) {
        Py_DECREF(result);
        stash(self);
        return false;
    }
    bool ok = (size_t)view.len == n;
    if (ok) {
        memcpy(rx, view.buf, n);
    } else {
        PyErr_Format(PyExc_ValueError, "ICM45686: transfer() returned %zd bytes for a %zu-byte transfer",
                     view.len, n);
        stash(self);
    }
    PyBuffer_Release(&view);
    Py_DECREF(result);
    return ok;
}

static void py_delay_ms(void *ctx, uint32_t ms) {
    ICM45686Object *self = ctx;
    if (self->delay_ms == NULL) {
        return; /* a register model answers at once */
    }
    PyObject *result = PyObject_CallFunction(self->delay_ms, "k", (unsigned long)ms);
    if (result == NULL) {
        stash(self);
    }
    Py_XDECREF(result);
}

static int icm45686_traverse(ICM45686Object *self, visitproc visit, void *arg) {
    Py_VISIT(self->transfer);
    Py_VISIT(self->delay_ms);
    Py_VISIT(Py_TYPE(self));
    return 0;
}

static int icm45686_clear(ICM45686Object *self) {
    Py_CLEAR(self->transfer);
    Py_CLEAR(self->delay_ms);
    Py_CLEAR(self->error_type);
    Py_CLEAR(self->error_value);
    Py_CLEAR(self->error_tb);
    return 0;
}

static void icm45686_dealloc(ICM45686Object *self) {
    PyTypeObject *type = Py_TYPE(self);
    PyObject_GC_UnTrack(self);
    icm45686_clear(self);
    type->tp_free((PyObject *)self);
    Py_DECREF(type);
}

static int icm45686_init(PyObject *self_in, PyObject *args, PyObject *kwargs) {
    static char *kwlist[] = {"transfer", "delay_ms", "scale", "sck", "mosi", "miso", "cs", "hz", "mode",
                             "spi_id", NULL};
    PyObject *transfer = Py_None, *delay_ms = Py_None, *pins[4] = {Py_None, Py_None, Py_None, Py_None};
    PyObject *hz = NULL, *mode = NULL, *spi_id = NULL;
    double scale = -1.0;
    if (!PyArg_ParseTupleAndKeywords(args, kwargs, "|O$OdOOOOOOO:ICM45686", kwlist, &transfer, &delay_ms, &scale,
                                     &pins[0], &pins[1], &pins[2], &pins[3], &hz, &mode, &spi_id)) {
        return -1;
    }
    (void)hz;
    (void)mode;
    (void)spi_id;
    if (pins[0] != Py_None || pins[1] != Py_None || pins[2] != Py_None || pins[3] != Py_None) {
        PyErr_SetString(PyExc_OSError, "ICM45686: this build has no SPI peripheral (only the ESP32 firmware reads "
                                       "pins); give transfer=<callable(bytes) -> bytes>");
        return -1;
    }
    if (!PyCallable_Check(transfer)) {
        PyErr_Format(PyExc_TypeError, "ICM45686(): transfer must be a callable(bytes) -> bytes, got %R", transfer);
        return -1;
    }
    if (delay_ms != Py_None && !PyCallable_Check(delay_ms)) {
        PyErr_Format(PyExc_TypeError, "ICM45686(): delay_ms must be a callable(ms) or None, got %R", delay_ms);
        return -1;
    }
    if (!isfinite(scale) || scale == 0.0) {
        PyErr_SetString(PyExc_ValueError,
                        "ICM45686(): scale must be non-zero: -1.0 for a face-up ICM-45686, +1.0 face-down");
        return -1;
    }
    ICM45686Object *self = (ICM45686Object *)self_in;
    icm45686_clear(self);
    self->transfer = Py_NewRef(transfer);
    self->delay_ms = delay_ms == Py_None ? NULL : Py_NewRef(delay_ms);
    ob_imu_yaw_config_t yaw_cfg;
    ob_imu_yaw_default_config(&yaw_cfg);
    yaw_cfg.scale = (float)scale;
    const ob_spi_t spi = {py_transfer, py_delay_ms, self};
    ob_icm45686_init(&self->imu, &spi, &yaw_cfg);
    ob_icm45686_error_t error = ob_icm45686_configure(&self->imu);
    if (raise_stashed(self) < 0) {
        return -1;
    }
    if (error == OB_ICM45686_NO_CHIP) {
        const char *hint = self->imu.who_am_i == 0x00 || self->imu.who_am_i == 0xFF
                               ? "nothing drives MISO: check wiring and 3V3"
                               : "another chip?";
        char msg[160];
        PyOS_snprintf(msg, sizeof msg, "no ICM-45686 on SPI: WHO_AM_I (0x72) reads 0x%02X, expected 0xE9; %s",
                      (unsigned)self->imu.who_am_i, hint);
        PyErr_SetString(PyExc_OSError, msg);
        return -1;
    }
    if (error != OB_ICM45686_OK) {
        PyErr_Format(PyExc_OSError, "ICM45686: %s", ob_icm45686_strerror(error));
        return -1;
    }
    return 0;
}

static PyObject *icm45686_sample(PyObject *self_in, PyObject *now_obj) {
    ICM45686Object *self = (ICM45686Object *)self_in;
    if (!PyLong_Check(now_obj)) {
        return PyErr_Format(PyExc_TypeError, "ICM45686.sample(): now_us must be an int (microseconds), not %.100s",
                            Py_TYPE(now_obj)->tp_name);
    }
    uint32_t now_us = (uint32_t)PyLong_AsUnsignedLongLongMask(now_obj);
    if (PyErr_Occurred()) {
        return NULL;
    }
    bool ok = ob_icm45686_sample(&self->imu, now_us);
    if (raise_stashed(self) < 0) {
        return NULL;
    }
    return PyBool_FromLong(ok);
}

static PyObject *icm45686_heading(PyObject *self, PyObject *unused) {
    (void)unused;
    return PyFloat_FromDouble(ob_imu_yaw_heading_deg(&((ICM45686Object *)self)->imu.yaw));
}

static PyObject *icm45686_rate(PyObject *self, PyObject *unused) {
    (void)unused;
    return PyFloat_FromDouble(ob_imu_yaw_rate_dps(&((ICM45686Object *)self)->imu.yaw));
}

static PyObject *icm45686_bias(PyObject *self, PyObject *unused) {
    (void)unused;
    return PyFloat_FromDouble(ob_imu_yaw_bias_dps(&((ICM45686Object *)self)->imu.yaw));
}

static PyObject *icm45686_calibrated(PyObject *self, PyObject *unused) {
    (void)unused;
    return PyBool_FromLong(ob_imu_yaw_calibrated(&((ICM45686Object *)self)->imu.yaw));
}

static PyObject *icm45686_reset_heading(PyObject *self, PyObject *args) {
    double heading_deg = 0.0;
    if (!PyArg_ParseTuple(args, "|d:reset_heading", &heading_deg)) {
        return NULL;
    }
    if (!isfinite(heading_deg)) {
        PyErr_SetString(PyExc_ValueError, "ICM45686.reset_heading(): heading must be a finite number");
        return NULL;
    }
    ob_imu_yaw_reset_heading(&((ICM45686Object *)self)->imu.yaw, (float)heading_deg);
    Py_RETURN_NONE;
}

static PyObject *icm45686_seed_bias(PyObject *self, PyObject *args) {
    return ob_py_imu_yaw_seed_bias(&((ICM45686Object *)self)->imu.yaw, args);
}

static PyObject *icm45686_gyro(PyObject *self, PyObject *unused) {
    (void)unused;
    const float *g = ((ICM45686Object *)self)->imu.last.gyro_dps;
    return Py_BuildValue("(ddd)", (double)g[0], (double)g[1], (double)g[2]);
}

static PyObject *icm45686_acceleration(PyObject *self, PyObject *unused) {
    (void)unused;
    const float *a = ((ICM45686Object *)self)->imu.last.accel_g;
    return Py_BuildValue("(ddd)", (double)a[0], (double)a[1], (double)a[2]);
}

static PyObject *icm45686_stats(PyObject *self, PyObject *unused) {
    (void)unused;
    const ob_icm45686_t *imu = &((ICM45686Object *)self)->imu;
    return Py_BuildValue("(kkO)", (unsigned long)imu->reads_ok, (unsigned long)imu->read_errors,
                         imu->configured ? Py_True : Py_False);
}

static PyObject *icm45686_close(PyObject *self, PyObject *unused) {
    (void)unused;
    ((ICM45686Object *)self)->imu.configured = false; /* later samples fail; the hub frees its SPI device */
    Py_RETURN_NONE;
}

static PyMethodDef icm45686_methods[] = {
    {"sample", icm45686_sample, METH_O,
     "sample(now_us) -> bool\n\nOne burst read at the microsecond clock now_us (the hub's hard tick does this "
     "every millisecond); False for a missed sample."},
    {"heading", icm45686_heading, METH_NOARGS, "heading() -> float\n\nContinuous heading, CW-positive, deg."},
    {"rate", icm45686_rate, METH_NOARGS, "rate() -> float\n\nBias-corrected heading rate, CW-positive, deg/s."},
    {"bias", icm45686_bias, METH_NOARGS, "bias() -> float\n\nGyro-Z bias estimate, deg/s: the value to persist."},
    {"calibrated", icm45686_calibrated, METH_NOARGS, "calibrated() -> bool\n\nTrue once the bias is known."},
    {"reset_heading", icm45686_reset_heading, METH_VARARGS,
     "reset_heading(heading=0.0)\n\nMake the current pose read `heading`; the bias is kept."},
    {"seed_bias", icm45686_seed_bias, METH_VARARGS, "seed_bias(bias_dps)\n\nUse a persisted bias now."},
    {"gyro", icm45686_gyro, METH_NOARGS, "gyro() -> (x, y, z)\n\nRates of the last good sample, deg/s."},
    {"acceleration", icm45686_acceleration, METH_NOARGS,
     "acceleration() -> (x, y, z)\n\nAcceleration of the last good sample, g."},
    {"stats", icm45686_stats, METH_NOARGS, "stats() -> (reads_ok, read_errors, configured)"},
    {"close", icm45686_close, METH_NOARGS, "close()\n\nStop sampling (the hub frees the SPI device)."},
    {NULL, NULL, 0, NULL},
};

static PyType_Slot icm45686_slots[] = {
    {Py_tp_doc, "ICM45686(transfer=None, *, delay_ms=None, scale=-1.0, sck=None, mosi=None, miso=None, cs=None, "
                "hz=8000000, mode=3, spi_id=1)\n\nThe ICM-45686 core: setup, burst read, gyro heading."},
    {Py_tp_init, icm45686_init},
    {Py_tp_new, PyType_GenericNew},
    {Py_tp_methods, icm45686_methods},
    {Py_tp_traverse, icm45686_traverse},
    {Py_tp_clear, icm45686_clear},
    {Py_tp_dealloc, icm45686_dealloc},
    {0, NULL},
};

static PyType_Spec icm45686_spec = {
    "openbricks_native.ICM45686",
    sizeof(ICM45686Object),
    0,
    Py_TPFLAGS_DEFAULT | Py_TPFLAGS_HAVE_GC | Py_TPFLAGS_BASETYPE,
    icm45686_slots,
};

int ob_py_icm45686_heading_source(PyObject *obj, ob_heading_source_t *source) {
    if (icm45686_type == NULL || !PyObject_TypeCheck(obj, icm45686_type)) {
        return 0;
    }
    source->read_heading = ob_icm45686_read_heading;
    source->ctx = &((ICM45686Object *)obj)->imu;
    return 1;
}

int ob_py_add_icm45686(PyObject *module) {
    PyObject *type = PyType_FromSpec(&icm45686_spec);
    if (type == NULL) {
        return -1;
    }
    /* The host reads no pins: the runtime keeps its own SPI driver (the simulator's chip) on builds like this. */
    int rc = PyObject_SetAttrString(type, "HARDWARE", Py_False);
    if (rc == 0) {
        rc = PyModule_AddObjectRef(module, "ICM45686", type);
    }
    if (rc == 0) {
        icm45686_type = (PyTypeObject *)Py_NewRef(type);
    }
    Py_DECREF(type);
    return rc;
}
