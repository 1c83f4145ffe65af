/*
 * openbricks_native.ImuYaw: the gyro heading integrator for the host, fed by
 * the simulator's IMU model and by the tests exactly as the hard tick feeds
 * it on the hub.
 */
#include <math.h>

#include "bindings.h"
#include "imu_yaw.h"

/* Longest settle window accepted: a minute of stillness is already far more than any robot waits. */
#define SETTLE_MS_MAX 60000.0

typedef struct {
    PyObject_HEAD
    ob_imu_yaw_t yaw;
} ImuYawObject;

static int require_finite(double value, const char *name) {
    if (!isfinite(value)) {
        PyErr_Format(PyExc_ValueError, "%s must be a finite number", name);
        return -1;
    }
    return 0;
}

static int require_range(double value, double lo, double hi, const char *name) {
    if (require_finite(value, name) < 0) {
        return -1;
    }
    if (value < lo || value > hi) {
        char msg[160];
        PyOS_snprintf(msg, sizeof msg, "%s must be in %g..%g, got %g", name, lo, hi, value);
        PyErr_SetString(PyExc_ValueError, msg);
        return -1;
    }
    return 0;
}

static int imu_yaw_init(PyObject *self, PyObject *args, PyObject *kwargs) {
    static char *kwlist[] = {"scale", "still_band_dps", "settle_ms", "track_tau_s", "max_bias_dps", NULL};
    ob_imu_yaw_config_t cfg;
    ob_imu_yaw_default_config(&cfg);
    double scale = cfg.scale, band = cfg.still_band_dps, settle_ms = cfg.settle_us / 1000.0;
    double tau = cfg.track_tau_s, max_bias = cfg.max_bias_dps;
    if (!PyArg_ParseTupleAndKeywords(args, kwargs, "|$ddddd:ImuYaw", kwlist, &scale, &band, &settle_ms, &tau,
                                     &max_bias)) {
        return -1;
    }
    if (require_finite(scale, "scale") < 0 || require_range(band, 1e-6, 1e3, "still_band_dps") < 0 ||
        require_range(settle_ms, 0.0, SETTLE_MS_MAX, "settle_ms") < 0 ||
        require_range(tau, 1e-3, 1e6, "track_tau_s") < 0 || require_range(max_bias, 1e-6, 1e3, "max_bias_dps") < 0) {
        return -1;
    }
    if (scale == 0.0) {
        PyErr_SetString(PyExc_ValueError, "scale must be non-zero (-1 for a face-up gyro, +1 for face-down)");
        return -1;
    }
    cfg.scale = (float)scale;
    cfg.still_band_dps = (float)band;
    cfg.settle_us = (uint32_t)(settle_ms * 1000.0 + 0.5);
    cfg.track_tau_s = (float)tau;
    cfg.max_bias_dps = (float)max_bias;
    ob_imu_yaw_init(&((ImuYawObject *)self)->yaw, &cfg);
    return 0;
}

static PyObject *imu_yaw_update(PyObject *self, PyObject *args) {
    double gyro_z_dps;
    PyObject *now_obj;
    if (!PyArg_ParseTuple(args, "dO:update", &gyro_z_dps, &now_obj)) {
        return NULL;
    }
    if (!PyLong_Check(now_obj)) {
        return PyErr_Format(PyExc_TypeError, "now_us must be an int (microseconds), not %.100s",
                            Py_TYPE(now_obj)->tp_name);
    }
    /* Only differences matter, so any integer clock works modulo 2**32, like the hub's. */
    uint32_t now_us = (uint32_t)PyLong_AsUnsignedLongLongMask(now_obj);
    if (PyErr_Occurred()) {
        return NULL;
    }
    ob_imu_yaw_update(&((ImuYawObject *)self)->yaw, (float)gyro_z_dps, now_us);
    Py_RETURN_NONE;
}

static PyObject *imu_yaw_heading(PyObject *self, PyObject *unused) {
    (void)unused;
    return PyFloat_FromDouble(ob_imu_yaw_heading_deg(&((ImuYawObject *)self)->yaw));
}

static PyObject *imu_yaw_rate(PyObject *self, PyObject *unused) {
    (void)unused;
    return PyFloat_FromDouble(ob_imu_yaw_rate_dps(&((ImuYawObject *)self)->yaw));
}

static PyObject *imu_yaw_bias(PyObject *self, PyObject *unused) {
    (void)unused;
    return PyFloat_FromDouble(ob_imu_yaw_bias_dps(&((ImuYawObject *)self)->yaw));
}

static PyObject *imu_yaw_calibrated(PyObject *self, PyObject *unused) {
    (void)unused;
    return PyBool_FromLong(ob_imu_yaw_calibrated(&((ImuYawObject *)self)->yaw));
}

static PyObject *imu_yaw_reset_heading(PyObject *self, PyObject *args) {
    double heading_deg = 0.0;
    if (!PyArg_ParseTuple(args, "|d:reset_heading", &heading_deg) ||
        require_finite(heading_deg, "heading") < 0) {
        return NULL;
    }
    ob_imu_yaw_reset_heading(&((ImuYawObject *)self)->yaw, (float)heading_deg);
    Py_RETURN_NONE;
}

PyObject *ob_py_imu_yaw_seed_bias(ob_imu_yaw_t *yaw, PyObject *args) {
    double bias_dps;
    if (!PyArg_ParseTuple(args, "d:seed_bias", &bias_dps)) {
        return NULL;
    }
    if (!ob_imu_yaw_seed_bias(yaw, (float)bias_dps)) {
        char msg[200];
        PyOS_snprintf(msg, sizeof msg,
                      "seed_bias(%g): a gyro bias must be finite and within +-%g deg/s (max_bias_dps); "
                      "the stored calibration looks corrupt, recalibrate at rest",
                      bias_dps, (double)yaw->cfg.max_bias_dps);
        PyErr_SetString(PyExc_ValueError, msg);
        return NULL;
    }
    Py_RETURN_NONE;
}

static PyObject *imu_yaw_seed_bias(PyObject *self, PyObject *args) {
    return ob_py_imu_yaw_seed_bias(&((ImuYawObject *)self)->yaw, args);
}

static PyMethodDef imu_yaw_methods[] = {
    {"update", imu_yaw_update, METH_VARARGS,
     "update(gyro_z_dps, now_us)\n\nOne gyro sample: Z rate as the sensor reports it (deg/s) and the "
     "microsecond clock when it was taken. The first sample only starts the clock; a NaN or infinite "
     "rate is dropped like a missed sample, as on the hub."},
    {"heading", imu_yaw_heading, METH_NOARGS, "heading() -> float\n\nContinuous heading, CW-positive, deg."},
    {"rate", imu_yaw_rate, METH_NOARGS,
     "rate() -> float\n\nBias-corrected heading rate of the last sample, CW-positive, deg/s."},
    {"bias", imu_yaw_bias, METH_NOARGS,
     "bias() -> float\n\nGyro-Z bias estimate in the sensor's deg/s: the value to persist."},
    {"calibrated", imu_yaw_calibrated, METH_NOARGS,
     "calibrated() -> bool\n\nTrue once a still window locked the bias or a bias was seeded."},
    {"reset_heading", imu_yaw_reset_heading, METH_VARARGS,
     "reset_heading(heading=0.0)\n\nMake the current pose read `heading`; the bias is kept."},
    {"seed_bias", imu_yaw_seed_bias, METH_VARARGS,
     "seed_bias(bias_dps)\n\nUse a persisted bias now (ValueError if not finite or beyond max_bias_dps)."},
    {NULL, NULL, 0, NULL},
};

static PyType_Slot imu_yaw_slots[] = {
    {Py_tp_doc, "ImuYaw(*, scale=-1.0, still_band_dps=1.5, settle_ms=500, track_tau_s=10.0, "
                "max_bias_dps=5.0)\n\nGyro-Z heading integrator with bias learning at rest (imu_yaw core)."},
    {Py_tp_init, imu_yaw_init},
    {Py_tp_new, PyType_GenericNew},
    {Py_tp_methods, imu_yaw_methods},
    {0, NULL},
};

static PyType_Spec imu_yaw_spec = {
    "openbricks_native.ImuYaw",
    sizeof(ImuYawObject),
    0,
    Py_TPFLAGS_DEFAULT,
    imu_yaw_slots,
};

int ob_py_add_imu_yaw(PyObject *module) {
    PyObject *type = PyType_FromSpec(&imu_yaw_spec);
    if (type == NULL) {
        return -1;
    }
    int rc = PyModule_AddObjectRef(module, "ImuYaw", type);
    Py_DECREF(type);
    return rc;
}
