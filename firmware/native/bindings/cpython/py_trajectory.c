/*
 * TrapezoidalProfile: the trajectory core as an immutable Python object, for
 * the tests, the simulator's planners and anyone plotting a move.
 */
#include "bindings.h"
#include "py_args.h"
#include "trajectory.h"

typedef struct {
    PyObject_HEAD
    ob_trajectory_t tr;
} ProfileObject;

static PyTypeObject ProfileType;

static PyObject *profile_wrap(const ob_trajectory_t *tr) {
    ProfileObject *self = PyObject_New(ProfileObject, &ProfileType);
    if (self != NULL) {
        self->tr = *tr;
    }
    return (PyObject *)self;
}

static int profile_init(ProfileObject *self, PyObject *args, PyObject *kwargs) {
    static char *kwlist[] = {"x0_deg",     "target_deg", "speed_dps",     "accel_dps2",
                             "decel_dps2", "v0_dps",     "end_at_cruise", NULL};
    static const char *where = "TrapezoidalProfile";
    PyObject *x0_obj, *target_obj, *speed_obj, *accel_obj, *decel_obj = Py_None, *v0_obj = NULL;
    int end_at_cruise = 0;
    if (!PyArg_ParseTupleAndKeywords(args, kwargs, "OOOO|OO$p:TrapezoidalProfile", kwlist, &x0_obj,
                                     &target_obj, &speed_obj, &accel_obj, &decel_obj, &v0_obj,
                                     &end_at_cruise)) {
        return -1;
    }
    float x0, target, speed, accel, decel, v0 = 0.0f;
    if (ob_py_float(x0_obj, where, "x0_deg", &x0) < 0 || ob_py_float(target_obj, where, "target_deg", &target) < 0 ||
        ob_py_positive_float(speed_obj, where, "speed_dps", &speed) < 0 ||
        ob_py_positive_float(accel_obj, where, "accel_dps2", &accel) < 0) {
        return -1;
    }
    decel = accel;
    if (decel_obj != Py_None && ob_py_positive_float(decel_obj, where, "decel_dps2", &decel) < 0) {
        return -1;
    }
    if (v0_obj != NULL && ob_py_float(v0_obj, where, "v0_dps", &v0) < 0) {
        return -1;
    }
    ob_trajectory_plan_move(&self->tr, x0, v0, target, speed, accel, decel, end_at_cruise != 0);
    return 0;
}

static PyObject *profile_speed_ramp(PyObject *cls, PyObject *args, PyObject *kwargs) {
    (void)cls;
    static char *kwlist[] = {"x0_deg", "v0_dps", "speed_dps", "accel_dps2", NULL};
    static const char *where = "TrapezoidalProfile.speed_ramp";
    PyObject *x0_obj, *v0_obj, *speed_obj, *accel_obj;
    if (!PyArg_ParseTupleAndKeywords(args, kwargs, "OOOO:speed_ramp", kwlist, &x0_obj, &v0_obj, &speed_obj,
                                     &accel_obj)) {
        return NULL;
    }
    float x0, v0, speed, accel;
    if (ob_py_float(x0_obj, where, "x0_deg", &x0) < 0 || ob_py_float(v0_obj, where, "v0_dps", &v0) < 0 ||
        ob_py_float(speed_obj, where, "speed_dps", &speed) < 0 ||
        ob_py_positive_float(accel_obj, where, "accel_dps2", &accel) < 0) {
        return NULL;
    }
    ob_trajectory_t tr;
    ob_trajectory_plan_speed(&tr, x0, v0, speed, accel);
    return profile_wrap(&tr);
}

static PyObject *profile_hold(PyObject *cls, PyObject *arg) {
    (void)cls;
    float x;
    if (ob_py_float(arg, "TrapezoidalProfile.hold", "x_deg", &x) < 0) {
        return NULL;
    }
    ob_trajectory_t tr;
    ob_trajectory_plan_hold(&tr, x);
    return profile_wrap(&tr);
}

static PyObject *profile_sample(ProfileObject *self, PyObject *arg) {
    float t;
    if (ob_py_float(arg, "TrapezoidalProfile.sample", "t_s", &t) < 0) {
        return NULL;
    }
    ob_trajectory_sample_t out;
    ob_trajectory_sample(&self->tr, t, &out);
    return Py_BuildValue("(ddd)", (double)out.x_deg, (double)out.v_dps, (double)out.a_dps2);
}

static PyObject *profile_scaled(ProfileObject *self, PyObject *args, PyObject *kwargs) {
    static char *kwlist[] = {"k", "x0_deg", NULL};
    static const char *where = "TrapezoidalProfile.scaled";
    PyObject *k_obj, *x0_obj;
    if (!PyArg_ParseTupleAndKeywords(args, kwargs, "OO:scaled", kwlist, &k_obj, &x0_obj)) {
        return NULL;
    }
    float k, x0;
    if (ob_py_float(k_obj, where, "k", &k) < 0 || ob_py_float(x0_obj, where, "x0_deg", &x0) < 0) {
        return NULL;
    }
    ob_trajectory_t tr;
    ob_trajectory_scaled(&self->tr, k, x0, &tr);
    return profile_wrap(&tr);
}

static PyObject *float_tuple(const float *values, int n) {
    PyObject *t = PyTuple_New(n);
    if (t == NULL) {
        return NULL;
    }
    for (int i = 0; i < n; i++) {
        PyObject *v = PyFloat_FromDouble((double)values[i]);
        if (v == NULL) {
            Py_DECREF(t);
            return NULL;
        }
        PyTuple_SET_ITEM(t, i, v);
    }
    return t;
}

static PyObject *profile_get_duration(ProfileObject *self, void *closure) {
    (void)closure;
    return PyFloat_FromDouble((double)ob_trajectory_duration_s(&self->tr));
}

static PyObject *profile_get_end(ProfileObject *self, void *closure) {
    (void)closure;
    return PyFloat_FromDouble((double)ob_trajectory_end_deg(&self->tr));
}

static PyObject *profile_get_times(ProfileObject *self, void *closure) {
    (void)closure;
    return float_tuple(self->tr.t_s, 3);
}

static PyObject *profile_get_positions(ProfileObject *self, void *closure) {
    (void)closure;
    return float_tuple(self->tr.x_deg, 4);
}

static PyObject *profile_get_speeds(ProfileObject *self, void *closure) {
    (void)closure;
    return float_tuple(self->tr.v_dps, 4);
}

static PyObject *profile_get_accels(ProfileObject *self, void *closure) {
    (void)closure;
    return float_tuple(self->tr.a_dps2, 3);
}

static PyObject *profile_repr(ProfileObject *self) {
    char text[160];
    PyOS_snprintf(text, sizeof(text), "TrapezoidalProfile(%.6g deg -> %.6g deg in %.6g s, tail %.6g deg/s)",
                  (double)self->tr.x_deg[0], (double)self->tr.x_deg[3], (double)self->tr.t_s[2],
                  (double)self->tr.v_dps[3]);
    return PyUnicode_FromString(text);
}

static PyMethodDef profile_methods[] = {
    {"sample", (PyCFunction)profile_sample, METH_O,
     "sample(t_s) -> (x_deg, v_dps, a_dps2) at t_s seconds after the start (t_s < 0 reads the start)."},
    {"scaled", (PyCFunction)(void (*)(void))profile_scaled, METH_VARARGS | METH_KEYWORDS,
     "scaled(k, x0_deg) -> the profile scaled by k in displacement, speed and acceleration, from x0_deg, "
     "with the same phase times: the two keep the ratio k at every instant."},
    {"speed_ramp", (PyCFunction)(void (*)(void))profile_speed_ramp, METH_VARARGS | METH_KEYWORDS | METH_CLASS,
     "speed_ramp(x0_deg, v0_dps, speed_dps, accel_dps2): ramp to speed_dps (signed), then keep it forever."},
    {"hold", (PyCFunction)profile_hold, METH_O | METH_CLASS, "hold(x_deg): stand still at x_deg."},
    {NULL, NULL, 0, NULL},
};

static PyGetSetDef profile_getset[] = {
    {"duration_s", (getter)profile_get_duration, NULL, "Seconds until the constant-speed tail.", NULL},
    {"end_deg", (getter)profile_get_end, NULL, "Position where the tail starts (the target of a move).", NULL},
    {"phase_end_s", (getter)profile_get_times, NULL, "End times of the accel, cruise and decel phases.", NULL},
    {"phase_x_deg", (getter)profile_get_positions, NULL, "Position at the start and at each phase end.", NULL},
    {"phase_v_dps", (getter)profile_get_speeds, NULL, "Speed at the start and at each phase end.", NULL},
    {"phase_a_dps2", (getter)profile_get_accels, NULL, "Constant acceleration within each phase.", NULL},
    {NULL, NULL, NULL, NULL, NULL},
};

static PyTypeObject ProfileType = {
    PyVarObject_HEAD_INIT(NULL, 0)
    .tp_name = "openbricks_native.TrapezoidalProfile",
    .tp_basicsize = sizeof(ProfileObject),
    .tp_flags = Py_TPFLAGS_DEFAULT,
    .tp_doc = "TrapezoidalProfile(x0_deg, target_deg, speed_dps, accel_dps2, decel_dps2=None, v0_dps=0.0, *, "
              "end_at_cruise=False)\n\n"
              "A move from x0_deg (moving at v0_dps) to target_deg: accelerate, cruise at speed_dps, decelerate, "
              "or a triangle when the move is too short to reach cruise. A start too fast to stop in time raises "
              "the deceleration just enough to land at rest on target. With end_at_cruise the move ends at "
              "target still moving (then=\"continue\"). decel_dps2 defaults to accel_dps2.",
    .tp_new = PyType_GenericNew,
    .tp_init = (initproc)profile_init,
    .tp_repr = (reprfunc)profile_repr,
    .tp_methods = profile_methods,
    .tp_getset = profile_getset,
};

int ob_py_add_trajectory(PyObject *module) {
    if (PyType_Ready(&ProfileType) < 0) {
        return -1;
    }
    Py_INCREF(&ProfileType);
    if (PyModule_AddObject(module, "TrapezoidalProfile", (PyObject *)&ProfileType) < 0) {
        Py_DECREF(&ProfileType);
        return -1;
    }
    return 0;
}
