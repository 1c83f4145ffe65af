/*
 * openbricks_mjcontrol: the simulator's per-millisecond path, in C.
 *
 * One MuJoCo step is one millisecond, and every step the hub's controllers
 * must read their encoders, compute and write duties, and the motors must
 * turn those duties into torque. Doing any of that in Python would cost more
 * than the physics itself, so the whole path lives here:
 *
 *   - Controller owns the simulated drive motors ("wheels"): where each
 *     wheel's joint angle, speed and actuator live inside mjData, and a
 *     DC-motor model per wheel (torque = stall * (duty - speed / no_load),
 *     i.e. back-EMF included; coasting applies no torque at all and leaves
 *     the joint's own friction, set in the model, to stop it).
 *   - WheelIO is a native motor IO provider (openbricks_native.MotorIO, see
 *     py_motor_io.h) onto one wheel, in the frame of whoever uses it (sign)
 *     and quantised to that motor's encoder counts. A Servo(io=...) or
 *     DriveBase(left_io=..., right_io=...) built on it reads and drives the
 *     wheel through C calls only.
 *   - control_step() is installed as MuJoCo's control callback. Each physics
 *     step it ticks the hub's motor_process (the runtime's controllers) and
 *     the world's own MotorProcess (firmware loops inside simulated devices,
 *     such as a serial-bus servo's speed loop) through openbricks_native's
 *     C-API, then writes every wheel's motor torque. Controller.step(n) arms
 *     it for exactly n steps and calls MuJoCo's C mj_step n times itself,
 *     holding the GIL: n milliseconds of controlled motion cost one Python
 *     call, and no step pays for giving the GIL away and taking it back (the
 *     ticks need it), which cost as much as the control itself. Other threads
 *     still get the GIL every STEPS_PER_GIL_RELEASE steps.
 *
 * The callback only acts while armed and only for the mjData it was built
 * for, so mj_forward calls made between steps (sensors, viewers) never tick
 * the controllers or advance the clock.
 */
#define PY_SSIZE_T_CLEAN
#include <Python.h>
#include <math.h>
#include <stdint.h>

#include "mjcontrol.h"

static const ob_py_capi_t *capi;

/* ---- Controller ---------------------------------------------------------------------------- */

static ControllerObject *active; /* the controller the callback serves (strong reference) */

static void keep_error(ControllerObject *self) {
    if (self->error_type == NULL) {
        PyErr_Fetch(&self->error_type, &self->error_value, &self->error_tb);
    } else {
        PyErr_WriteUnraisable(NULL); /* a later error of the same run: reported, not lost */
    }
}

static inline void apply_torques(ControllerObject *self) {
    for (int i = 0; i < self->n_wheels; i++) {
        wheel_t *w = &self->wheels[i];
        double torque = 0.0;
        if (!w->coasting) {
            torque = w->torque_scale * w->stall_torque_nm * (w->duty - *w->qvel * w->inv_no_load_rad_s);
        }
        w->torque_nm = torque;
        *w->ctrl = torque;
    }
}

/* MuJoCo's mjfGeneric control callback: void (const mjModel *, mjData *). */
static void control_step(const void *model, void *data) {
    (void)model;
    ControllerObject *self = active;
    if (self == NULL || self->armed <= 0 || data != self->data_address) {
        return;
    }
    self->armed--;
    uint32_t now_ms = (uint32_t)self->now_ms;
    /* The ticks handle Python objects. Controller.step holds the GIL, so this is a check, but an
     * mj_step called from elsewhere (mujoco.mj_step releases the GIL) must take it. */
    PyGILState_STATE gil = PyGILState_Ensure();
    if (capi->motor_process_tick(capi->motor_process, now_ms) < 0) {
        keep_error(self);
    }
    if (self->world != NULL && capi->motor_process_tick(self->world, now_ms) < 0) {
        keep_error(self);
    }
    PyGILState_Release(gil);
    apply_torques(self);
    self->now_ms++;
}

/* A contiguous float64 array attribute of MjData, as a raw pointer and a length. */
static int double_array(PyObject *data, const char *name, double **out, Py_ssize_t *len) {
    PyObject *array = PyObject_GetAttrString(data, name);
    if (array == NULL) {
        return -1;
    }
    Py_buffer view;
    int rc = PyObject_GetBuffer(array, &view, PyBUF_C_CONTIGUOUS | PyBUF_FORMAT);
    Py_DECREF(array);
    if (rc < 0) {
        return -1;
    }
    if (view.format == NULL || strcmp(view.format, "d") != 0 || view.itemsize != sizeof(double)) {
        PyErr_Format(PyExc_TypeError, "Controller: MjData.%s is not a float64 array", name);
        PyBuffer_Release(&view);
        return -1;
    }
    /* The memory belongs to mjData, which the controller keeps alive; only the view is released. */
    *out = (double *)view.buf;
    *len = view.len / (Py_ssize_t)sizeof(double);
    PyBuffer_Release(&view);
    return 0;
}

static int ctl_init(ControllerObject *self, PyObject *args, PyObject *kwargs) {
    static char *kwlist[] = {"model", "data", "mj_step", "world", NULL};
    PyObject *model, *data, *mj_step, *world = Py_None;
    if (!PyArg_ParseTupleAndKeywords(args, kwargs, "OOO|O:Controller", kwlist, &model, &data, &mj_step, &world)) {
        return -1;
    }
    if (self->data != NULL) {
        /* WheelIO objects and the wheels point into the mjData this controller was built on. */
        PyErr_SetString(PyExc_RuntimeError,
                        "Controller is already initialised; its wheels point into the MjData it was built on. "
                        "Build a new Controller for another model or data");
        return -1;
    }
    if (world != Py_None && !PyObject_TypeCheck(world, capi->motor_process_type)) {
        PyErr_Format(PyExc_TypeError, "Controller: world must be an openbricks_native.MotorProcess or None, not %.100s",
                     Py_TYPE(world)->tp_name);
        return -1;
    }
    PyObject *address = PyObject_GetAttrString(data, "_address");
    if (address == NULL) {
        return -1;
    }
    void *data_address = PyLong_AsVoidPtr(address);
    Py_DECREF(address);
    if (data_address == NULL) {
        if (!PyErr_Occurred()) {
            PyErr_SetString(PyExc_ValueError, "Controller: MjData has no address");
        }
        return -1;
    }
    double *qpos, *qvel, *ctrl;
    Py_ssize_t nq, nv, nu;
    if (double_array(data, "qpos", &qpos, &nq) < 0 || double_array(data, "qvel", &qvel, &nv) < 0 ||
        double_array(data, "ctrl", &ctrl, &nu) < 0) {
        return -1;
    }
    PyObject *model_address_obj = PyObject_GetAttrString(model, "_address");
    if (model_address_obj == NULL) {
        return -1;
    }
    void *model_address = PyLong_AsVoidPtr(model_address_obj);
    Py_DECREF(model_address_obj);
    mj_step_fn step_fn = (mj_step_fn)PyLong_AsVoidPtr(mj_step);
    if (model_address == NULL || step_fn == NULL) {
        if (!PyErr_Occurred()) {
            PyErr_SetString(PyExc_ValueError, "Controller: needs the MjModel's address and mj_step's (nonzero)");
        }
        return -1;
    }
    self->model_address = model_address;
    self->mj_step = step_fn;
    Py_XSETREF(self->model, Py_NewRef(model));
    Py_XSETREF(self->data, Py_NewRef(data));
    Py_XSETREF(self->world, world == Py_None ? NULL : Py_NewRef(world));
    self->data_address = data_address;
    self->qpos = qpos;
    self->qvel = qvel;
    self->ctrl = ctrl;
    self->nq = nq;
    self->nv = nv;
    self->nu = nu;
    self->n_wheels = 0;
    self->now_ms = 0;
    self->armed = 0;
    return 0;
}

static int ctl_traverse(ControllerObject *self, visitproc visit, void *arg) {
    Py_VISIT(self->model);
    Py_VISIT(self->data);
    Py_VISIT(self->world);
    Py_VISIT(self->error_type);
    Py_VISIT(self->error_value);
    Py_VISIT(self->error_tb);
    return 0;
}

static int ctl_clear(ControllerObject *self) {
    self->n_wheels = 0; /* the arrays go with data */
    self->data_address = NULL;
    Py_CLEAR(self->model);
    Py_CLEAR(self->data);
    Py_CLEAR(self->world);
    Py_CLEAR(self->error_type);
    Py_CLEAR(self->error_value);
    Py_CLEAR(self->error_tb);
    return 0;
}

static void ctl_dealloc(ControllerObject *self) {
    PyObject_GC_UnTrack(self);
    ctl_clear(self);
    Py_TYPE(self)->tp_free((PyObject *)self);
}

static int ready(ControllerObject *self, const char *where) {
    if (self->data == NULL) {
        PyErr_Format(PyExc_RuntimeError, "Controller.%s: the controller was never initialised", where);
        return -1;
    }
    return 0;
}

static PyObject *ctl_add_wheel(ControllerObject *self, PyObject *args, PyObject *kwargs) {
    static char *kwlist[] = {"qpos_index", "dof_index", "actuator_index", "stall_torque_nm", "no_load_speed_dps",
                             NULL};
    Py_ssize_t qi, vi, ui;
    double stall, no_load_dps;
    if (!PyArg_ParseTupleAndKeywords(args, kwargs, "nnndd:add_wheel", kwlist, &qi, &vi, &ui, &stall,
                                     &no_load_dps)) {
        return NULL;
    }
    if (ready(self, "add_wheel") < 0) {
        return NULL;
    }
    if (self->n_wheels >= MAX_WHEELS) {
        PyErr_Format(PyExc_ValueError, "Controller.add_wheel: at most %d motors per robot", MAX_WHEELS);
        return NULL;
    }
    if (qi < 0 || qi >= self->nq || vi < 0 || vi >= self->nv || ui < 0 || ui >= self->nu) {
        PyErr_Format(PyExc_IndexError,
                     "Controller.add_wheel: qpos %zd / dof %zd / actuator %zd out of range (nq=%zd, nv=%zd, nu=%zd)",
                     qi, vi, ui, self->nq, self->nv, self->nu);
        return NULL;
    }
    if (!(stall > 0.0 && isfinite(stall)) || !(no_load_dps > 0.0 && isfinite(no_load_dps))) {
        PyErr_SetString(PyExc_ValueError,
                        "Controller.add_wheel: stall_torque_nm and no_load_speed_dps must be positive and finite");
        return NULL;
    }
    wheel_t *w = &self->wheels[self->n_wheels];
    w->qpos = self->qpos + qi;
    w->qvel = self->qvel + vi;
    w->ctrl = self->ctrl + ui;
    w->stall_torque_nm = stall;
    w->inv_no_load_rad_s = 1.0 / (no_load_dps / RAD_TO_DEG);
    w->torque_scale = 1.0;
    w->coasting = 1;
    w->duty = 0.0;
    w->torque_nm = 0.0;
    *w->ctrl = 0.0;
    return PyLong_FromLong(self->n_wheels++);
}

static int wheel_arg(ControllerObject *self, PyObject *obj, const char *where, int *out) {
    long index = PyLong_AsLong(obj);
    if (index == -1 && PyErr_Occurred()) {
        return -1;
    }
    if (index < 0 || index >= self->n_wheels) {
        PyErr_Format(PyExc_IndexError, "Controller.%s: no wheel %ld (this robot has %d)", where, index,
                     self->n_wheels);
        return -1;
    }
    *out = (int)index;
    return 0;
}

static PyObject *ctl_set_torque_scale(ControllerObject *self, PyObject *args) {
    PyObject *wheel_obj;
    double scale;
    int wheel;
    if (!PyArg_ParseTuple(args, "Od:set_torque_scale", &wheel_obj, &scale) ||
        wheel_arg(self, wheel_obj, "set_torque_scale", &wheel) < 0) {
        return NULL;
    }
    if (!(scale >= 0.0 && scale <= 10.0)) {
        PyErr_Format(PyExc_ValueError, "Controller.set_torque_scale: scale must be within 0..10, got %g", scale);
        return NULL;
    }
    self->wheels[wheel].torque_scale = scale;
    Py_RETURN_NONE;
}

static PyObject *ctl_wheel_torque(ControllerObject *self, PyObject *arg) {
    int wheel;
    if (wheel_arg(self, arg, "wheel_torque_nm", &wheel) < 0) {
        return NULL;
    }
    return PyFloat_FromDouble(self->wheels[wheel].torque_nm);
}

static PyObject *ctl_activate(ControllerObject *self, PyObject *unused) {
    (void)unused;
    if (ready(self, "activate") < 0) {
        return NULL;
    }
    Py_INCREF(self);
    Py_XSETREF(active, self);
    Py_RETURN_NONE;
}

static PyObject *ctl_deactivate(ControllerObject *self, PyObject *unused) {
    (void)unused;
    if (active == self) {
        Py_CLEAR(active);
    }
    Py_RETURN_NONE;
}

static PyObject *ctl_step(ControllerObject *self, PyObject *arg) {
    long n = PyLong_AsLong(arg);
    if (n == -1 && PyErr_Occurred()) {
        return NULL;
    }
    if (n < 0) {
        PyErr_Format(PyExc_ValueError, "Controller.step: n must be >= 0 steps, got %ld", n);
        return NULL;
    }
    if (ready(self, "step") < 0) {
        return NULL;
    }
    if (active != self) {
        PyErr_SetString(PyExc_RuntimeError,
                        "Controller.step: this controller is not the active one; call activate() first (and "
                        "install control_callback_address() with mujoco.set_mjcb_control)");
        return NULL;
    }
    if (n == 0) {
        Py_RETURN_NONE;
    }
    uint64_t start_ms = self->now_ms;
    self->armed = n;
    for (long i = 1; i <= n; i++) {
        self->mj_step(self->model_address, self->data_address);
        if (i % STEPS_PER_GIL_RELEASE == 0) {
            Py_BEGIN_ALLOW_THREADS
            Py_END_ALLOW_THREADS
        }
    }
    long missed = self->armed;
    self->armed = 0;
    if (self->error_type != NULL) {
        PyErr_Restore(self->error_type, self->error_value, self->error_tb);
        self->error_type = self->error_value = self->error_tb = NULL;
        return NULL;
    }
    if (missed != 0 || self->now_ms != start_ms + (uint64_t)n) {
        PyErr_Format(PyExc_RuntimeError,
                     "Controller.step: the control callback ran %ld of %ld steps; is "
                     "control_callback_address() installed with mujoco.set_mjcb_control?",
                     n - missed, n);
        return NULL;
    }
    Py_RETURN_NONE;
}

static PyObject *ctl_get_now_ms(ControllerObject *self, void *closure) {
    (void)closure;
    return PyLong_FromUnsignedLongLong(self->now_ms);
}

/* A simulation whose physics is built when the program first touches the hardware starts its clock
 * where the program's time already is. */
static int ctl_set_now_ms(ControllerObject *self, PyObject *value, void *closure) {
    (void)closure;
    if (value == NULL) {
        PyErr_SetString(PyExc_AttributeError, "Controller.now_ms cannot be deleted");
        return -1;
    }
    unsigned long long now_ms = PyLong_AsUnsignedLongLong(value);
    if (now_ms == (unsigned long long)-1 && PyErr_Occurred()) {
        return -1;
    }
    if (self->armed > 0) {
        PyErr_SetString(PyExc_RuntimeError, "Controller.now_ms cannot change while it steps");
        return -1;
    }
    self->now_ms = now_ms;
    return 0;
}

static PyObject *ctl_get_n_wheels(ControllerObject *self, void *closure) {
    (void)closure;
    return PyLong_FromLong(self->n_wheels);
}

static PyObject *ctl_get_world(ControllerObject *self, void *closure) {
    (void)closure;
    return Py_NewRef(self->world != NULL ? self->world : Py_None);
}

static PyMethodDef ctl_methods[] = {
    {"add_wheel", (PyCFunction)(void (*)(void))ctl_add_wheel, METH_VARARGS | METH_KEYWORDS,
     "add_wheel(qpos_index, dof_index, actuator_index, stall_torque_nm, no_load_speed_dps) -> wheel index: "
     "drive a hinge joint through its torque actuator with a DC-motor model."},
    {"set_torque_scale", (PyCFunction)ctl_set_torque_scale, METH_VARARGS,
     "set_torque_scale(wheel, scale): scale the wheel's motor torque (0.9 = a motor 10 % weaker)."},
    {"wheel_torque_nm", (PyCFunction)ctl_wheel_torque, METH_O, "Motor torque applied in the last step."},
    {"activate", (PyCFunction)ctl_activate, METH_NOARGS, "Make this the controller the control callback serves."},
    {"deactivate", (PyCFunction)ctl_deactivate, METH_NOARGS, "Stop serving this controller."},
    {"step", (PyCFunction)ctl_step, METH_O,
     "step(n): n controlled physics steps (n ms), MuJoCo's mj_step called from C. Raises the first error "
     "a tick raised, once the steps are done."},
    {NULL, NULL, 0, NULL},
};

static PyGetSetDef ctl_getset[] = {
    {"now_ms", (getter)ctl_get_now_ms, (setter)ctl_set_now_ms,
     "Simulated milliseconds: where the clock started plus the controlled steps run since.", NULL},
    {"n_wheels", (getter)ctl_get_n_wheels, NULL, "Number of wheels added.", NULL},
    {"world", (getter)ctl_get_world, NULL, "The world's MotorProcess (simulated device firmware), or None.",
     NULL},
    {NULL, NULL, NULL, NULL, NULL},
};

static PyTypeObject ControllerType = {
    PyVarObject_HEAD_INIT(NULL, 0)
    .tp_name = "openbricks_mjcontrol.Controller",
    .tp_basicsize = sizeof(ControllerObject),
    .tp_flags = Py_TPFLAGS_DEFAULT | Py_TPFLAGS_HAVE_GC,
    .tp_doc = "Controller(model, data, mj_step, world=None)\n\n"
              "The simulated robot's motors and the per-step control callback: each physics step ticks the hub's "
              "motor_process and the world's MotorProcess, then applies every wheel's DC-motor torque.",
    .tp_new = PyType_GenericNew,
    .tp_init = (initproc)ctl_init,
    .tp_dealloc = (destructor)ctl_dealloc,
    .tp_traverse = (traverseproc)ctl_traverse,
    .tp_clear = (inquiry)ctl_clear,
    .tp_methods = ctl_methods,
    .tp_getset = ctl_getset,
};

/* ---- WheelIO -------------------------------------------------------------------------------- */

static bool wheel_read_angle(void *ctx, float *angle_deg) {
    WheelIOObject *self = ctx;
    if (self->silent) {
        self->failed++;
        self->failed_in_a_row++;
        return false;
    }
    self->replies++;
    self->failed_in_a_row = 0;
    double counts = nearbyint(self->sign * *self->wheel->qpos * self->counts_per_rad);
    *angle_deg = (float)(counts * self->deg_per_count);
    return true;
}

static void wheel_write_duty(void *ctx, float duty_pct) {
    WheelIOObject *self = ctx;
    if (self->silent) {
        return;
    }
    double duty = self->sign * (double)duty_pct / 100.0;
    self->wheel->duty = duty > 1.0 ? 1.0 : (duty < -1.0 ? -1.0 : duty);
    self->wheel->coasting = 0;
}

static void wheel_write_coast(void *ctx) {
    WheelIOObject *self = ctx;
    if (self->silent) {
        return;
    }
    self->wheel->coasting = 1;
}

static int wio_init(WheelIOObject *self, PyObject *args, PyObject *kwargs) {
    static char *kwlist[] = {"controller", "wheel", "sign", "counts_per_rev", NULL};
    PyObject *controller, *wheel_obj;
    int sign = 1;
    double counts_per_rev = 4096.0;
    if (!PyArg_ParseTupleAndKeywords(args, kwargs, "O!O|id:WheelIO", kwlist, &ControllerType, &controller,
                                     &wheel_obj, &sign, &counts_per_rev)) {
        return -1;
    }
    ControllerObject *owner = (ControllerObject *)controller;
    int index;
    if (wheel_arg(owner, wheel_obj, "WheelIO", &index) < 0) {
        return -1;
    }
    if (sign != 1 && sign != -1) {
        PyErr_Format(PyExc_ValueError, "WheelIO: sign must be 1 or -1, got %d", sign);
        return -1;
    }
    if (!(counts_per_rev >= 1.0 && isfinite(counts_per_rev))) {
        PyErr_Format(PyExc_ValueError, "WheelIO: counts_per_rev must be >= 1, got %g", counts_per_rev);
        return -1;
    }
    Py_INCREF(owner);
    Py_XSETREF(self->owner, owner);
    self->wheel = &owner->wheels[index];
    self->index = index;
    self->sign = (double)sign;
    self->counts_per_rad = counts_per_rev / (2.0 * 3.14159265358979323846);
    self->deg_per_count = 360.0 / counts_per_rev;
    self->silent = 0;
    self->replies = self->failed = self->failed_in_a_row = 0;
    self->base.io = (ob_motor_io_t){wheel_read_angle, wheel_write_duty, wheel_write_coast, self};
    return 0;
}

static int wio_traverse(WheelIOObject *self, visitproc visit, void *arg) {
    Py_VISIT(self->owner);
    return 0;
}

static int wio_clear(WheelIOObject *self) {
    /* The functions stay set: a consumer holding this IO keeps a reference, so this only runs once none does. */
    Py_CLEAR(self->owner);
    return 0;
}

static void wio_dealloc(WheelIOObject *self) {
    PyObject_GC_UnTrack(self);
    wio_clear(self);
    Py_TYPE(self)->tp_free((PyObject *)self);
}

static int wio_ready(WheelIOObject *self) {
    if (self->owner == NULL) {
        PyErr_SetString(PyExc_RuntimeError, "WheelIO was never initialised");
        return -1;
    }
    return 0;
}

static PyObject *wio_py_read_angle(WheelIOObject *self, PyObject *unused) {
    (void)unused;
    if (wio_ready(self) < 0) {
        return NULL;
    }
    float angle;
    if (!wheel_read_angle(self, &angle)) {
        Py_RETURN_NONE;
    }
    return PyFloat_FromDouble((double)angle);
}

static PyObject *wio_py_write_duty(WheelIOObject *self, PyObject *arg) {
    double duty = PyFloat_AsDouble(arg);
    if (duty == -1.0 && PyErr_Occurred()) {
        return NULL;
    }
    if (!isfinite(duty)) {
        PyErr_Format(PyExc_ValueError, "WheelIO.write_duty: duty_pct must be finite, got %R", arg);
        return NULL;
    }
    if (wio_ready(self) < 0) {
        return NULL;
    }
    wheel_write_duty(self, (float)duty);
    Py_RETURN_NONE;
}

static PyObject *wio_py_coast(WheelIOObject *self, PyObject *unused) {
    (void)unused;
    if (wio_ready(self) < 0) {
        return NULL;
    }
    wheel_write_coast(self);
    Py_RETURN_NONE;
}

static PyObject *wio_get_speed(WheelIOObject *self, void *closure) {
    (void)closure;
    if (wio_ready(self) < 0) {
        return NULL;
    }
    return PyFloat_FromDouble(self->sign * *self->wheel->qvel * RAD_TO_DEG);
}

static PyObject *wio_get_true_angle(WheelIOObject *self, void *closure) {
    (void)closure;
    if (wio_ready(self) < 0) {
        return NULL;
    }
    return PyFloat_FromDouble(self->sign * *self->wheel->qpos * RAD_TO_DEG);
}

static PyObject *wio_get_duty(WheelIOObject *self, void *closure) {
    (void)closure;
    if (wio_ready(self) < 0) {
        return NULL;
    }
    if (self->wheel->coasting) {
        Py_RETURN_NONE;
    }
    return PyFloat_FromDouble(self->sign * self->wheel->duty * 100.0);
}

static PyObject *wio_get_torque(WheelIOObject *self, void *closure) {
    (void)closure;
    if (wio_ready(self) < 0) {
        return NULL;
    }
    return PyFloat_FromDouble(self->sign * self->wheel->torque_nm);
}

static PyObject *wio_get_silent(WheelIOObject *self, void *closure) {
    (void)closure;
    return PyBool_FromLong(self->silent);
}

static int wio_set_silent(WheelIOObject *self, PyObject *value, void *closure) {
    (void)closure;
    if (value == NULL) {
        PyErr_SetString(PyExc_AttributeError, "WheelIO.silent cannot be deleted");
        return -1;
    }
    int flag = PyObject_IsTrue(value);
    if (flag < 0) {
        return -1;
    }
    self->silent = flag;
    return 0;
}

static PyObject *wio_get_stats(WheelIOObject *self, void *closure) {
    (void)closure;
    return Py_BuildValue("(kkk)", self->replies, self->failed, self->failed_in_a_row);
}

static PyObject *wio_get_wheel(WheelIOObject *self, void *closure) {
    (void)closure;
    return PyLong_FromLong(self->index);
}

static PyObject *wio_get_sign(WheelIOObject *self, void *closure) {
    (void)closure;
    return PyLong_FromLong((long)self->sign);
}

static PyMethodDef wio_methods[] = {
    {"read_angle", (PyCFunction)wio_py_read_angle, METH_NOARGS,
     "The encoder angle in degrees (quantised, this IO's frame), or None while silent."},
    {"write_duty", (PyCFunction)wio_py_write_duty, METH_O, "write_duty(duty_pct): drive the motor, -100..100."},
    {"coast", (PyCFunction)wio_py_coast, METH_NOARGS, "Release the motor."},
    {NULL, NULL, 0, NULL},
};

static PyGetSetDef wio_getset[] = {
    {"speed_dps", (getter)wio_get_speed, NULL, "True shaft speed in this IO's frame (deg/s).", NULL},
    {"true_angle_deg", (getter)wio_get_true_angle, NULL, "Unquantised shaft angle in this IO's frame.", NULL},
    {"duty_pct", (getter)wio_get_duty, NULL, "Commanded duty in this IO's frame, or None while coasting.", NULL},
    {"torque_nm", (getter)wio_get_torque, NULL, "Motor torque applied in the last step, this IO's frame.", NULL},
    {"silent", (getter)wio_get_silent, (setter)wio_set_silent,
     "True makes the motor unplugged: reads fail, commands are ignored.", NULL},
    {"stats", (getter)wio_get_stats, NULL, "(replies, failed_reads, failed_in_a_row) of angle reads.", NULL},
    {"wheel", (getter)wio_get_wheel, NULL, "Index of the wheel in its Controller.", NULL},
    {"sign", (getter)wio_get_sign, NULL, "1, or -1 when this IO sees the joint mirrored.", NULL},
    {NULL, NULL, NULL, NULL, NULL},
};

PyTypeObject WheelIOType = {
    PyVarObject_HEAD_INIT(NULL, 0)
    .tp_name = "openbricks_mjcontrol.WheelIO",
    .tp_basicsize = sizeof(WheelIOObject),
    .tp_flags = Py_TPFLAGS_DEFAULT | Py_TPFLAGS_HAVE_GC,
    .tp_doc = "WheelIO(controller, wheel, sign=1, counts_per_rev=4096)\n\n"
              "Native motor IO onto one simulated wheel: pass it to Servo(io=...) or "
              "DriveBase(left_io=..., right_io=...) and they read the encoder and drive the motor in C.",
    .tp_new = PyType_GenericNew,
    .tp_init = (initproc)wio_init,
    .tp_dealloc = (destructor)wio_dealloc,
    .tp_traverse = (traverseproc)wio_traverse,
    .tp_clear = (inquiry)wio_clear,
    .tp_methods = wio_methods,
    .tp_getset = wio_getset,
};

/* ---- module --------------------------------------------------------------------------------- */

static PyObject *mod_callback_address(PyObject *module, PyObject *unused) {
    (void)module;
    (void)unused;
    return PyLong_FromVoidPtr((void *)(uintptr_t)control_step);
}

static PyMethodDef module_methods[] = {
    {"control_callback_address", mod_callback_address, METH_NOARGS,
     "Address of the C control callback, for mujoco.set_mjcb_control(ctypes.CFUNCTYPE(None, c_void_p, "
     "c_void_p)(address))."},
    {NULL, NULL, 0, NULL},
};

static struct PyModuleDef module_def = {
    PyModuleDef_HEAD_INIT,
    "openbricks_mjcontrol",
    "The simulator's per-millisecond control path in C: wheel motor models, native wheel IO for the control "
    "cores, and the MuJoCo control callback that ticks them.",
    -1,
    module_methods,
    NULL,
    NULL,
    NULL,
    NULL,
};

PyMODINIT_FUNC PyInit_openbricks_mjcontrol(void) {
    capi = ob_py_capi_import();
    if (capi == NULL) {
        return NULL;
    }
    WheelIOType.tp_base = capi->motor_io_type;
    if (PyType_Ready(&ControllerType) < 0 || PyType_Ready(&WheelIOType) < 0) {
        return NULL;
    }
    PyObject *m = PyModule_Create(&module_def);
    if (m == NULL) {
        return NULL;
    }
    if (PyModule_AddObjectRef(m, "Controller", (PyObject *)&ControllerType) < 0 ||
        PyModule_AddObjectRef(m, "WheelIO", (PyObject *)&WheelIOType) < 0 || ob_sim_add_servo_wire(m) < 0) {
        Py_DECREF(m);
        return NULL;
    }
    return m;
}
