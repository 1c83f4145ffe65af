/*
 * Servo: the servo core for the host, in two flavours of IO.
 *
 * - Python-callable IO, for the runtime's encoder motors (JGB37, MG370):
 *   Servo(read_angle=f, write_duty=g, write_coast=h). read_angle() returns
 *   the angle in degrees, or None when no fresh reading is available.
 *   Subscribe the servo to motor_process and it is ticked natively; only the
 *   IO crosses into Python.
 * - The direct path, for host loops: Servo() with no callables, and
 *   update(now_ms, measured_deg) -> duty_pct (None while coasting) runs one
 *   control step with no Python call at all.
 * - Native IO, for the simulator's wheels: Servo(io=provider) with a
 *   MotorIO-derived object (py_motor_io.h); motor_process then ticks it with
 *   no Python call at all.
 *
 * Exceptions raised by the IO callables cannot cross the core's C frames, so
 * they are stashed while the core runs and raised when it returns. A read
 * that raises counts as a failed read, so the core's silent-feedback halt
 * protects the motor whatever the caller does with the exception.
 */
#include <stddef.h>

#include "bindings.h"
#include "py_args.h"
#include "py_motor_io.h"
#include "py_subscriber.h"
#include "servo.h"
#include "servo_settings.h"

typedef struct {
    ob_py_subscriber_t base;
    ob_servo_t servo;
    PyObject *read_angle; /* NULL on the direct path */
    PyObject *native_io;  /* MotorIO provider (io=), or NULL */
    PyObject *write_duty;
    PyObject *write_coast;
    PyObject *error_type; /* first error raised by a callable during the current call */
    PyObject *error_value;
    PyObject *error_tb;
} ServoObject;

static PyTypeObject ServoType;

/* ---- Stashing callable errors across the core. ---- */

static void stash_error(ServoObject *self) {
    if (self->error_type == NULL) {
        PyErr_Fetch(&self->error_type, &self->error_value, &self->error_tb);
    } else {
        PyErr_WriteUnraisable(NULL); /* a second error in one call: report it, keep the first */
    }
}

/* Re-raise the stashed error, if any. Returns -1 when one was raised. */
static int raise_stashed(ServoObject *self) {
    if (self->error_type == NULL) {
        return 0;
    }
    PyErr_Restore(self->error_type, self->error_value, self->error_tb);
    self->error_type = self->error_value = self->error_tb = NULL;
    return -1;
}

/* ---- IO adapters. ---- */

static bool py_read_angle(void *ctx, float *angle_deg) {
    ServoObject *self = (ServoObject *)ctx;
    PyObject *result = PyObject_CallNoArgs(self->read_angle);
    if (result == NULL) {
        stash_error(self);
        return false;
    }
    if (result == Py_None) {
        Py_DECREF(result);
        return false;
    }
    float value;
    int rc = ob_py_float(result, "Servo", "the value returned by read_angle", &value);
    Py_DECREF(result);
    if (rc < 0) {
        stash_error(self);
        return false;
    }
    *angle_deg = value;
    return true;
}

static void py_write_duty(void *ctx, float duty_pct) {
    ServoObject *self = (ServoObject *)ctx;
    PyObject *arg = PyFloat_FromDouble((double)duty_pct);
    PyObject *result = arg != NULL ? PyObject_CallOneArg(self->write_duty, arg) : NULL;
    Py_XDECREF(arg);
    if (result == NULL) {
        stash_error(self);
        return;
    }
    Py_DECREF(result);
}

static void py_write_coast(void *ctx) {
    ServoObject *self = (ServoObject *)ctx;
    PyObject *result = PyObject_CallNoArgs(self->write_coast);
    if (result == NULL) {
        stash_error(self);
        return;
    }
    Py_DECREF(result);
}

/* Subscriber tick: the core's tick, then any callable error for motor_process. */
static void servo_tick_fn(void *ctx, uint32_t now_ms) {
    ServoObject *self = (ServoObject *)ctx;
    ob_servo_tick(&self->servo, now_ms);
    raise_stashed(self);
}

/* ---- Settings: the core's table (servo_settings.h) checks them; this only parses. ---- */

static int set_one(ob_servo_config_t *cfg, const char *name, PyObject *value, const char *where) {
    char msg[OB_SERVO_SETTING_MSG_SIZE];
    const ob_servo_setting_t *setting = ob_servo_setting_find(name, where, msg, sizeof(msg));
    if (setting == NULL) {
        PyErr_SetString(PyExc_TypeError, msg);
        return -1;
    }
    bool is_int = PyLong_Check(value) && !PyBool_Check(value);
    double number = 0.0;
    if (is_int || !setting->is_ms) {
        float parsed;
        if (ob_py_float(value, where, setting->name, &parsed) < 0) {
            return -1;
        }
        number = is_int ? PyLong_AsDouble(value) : (double)parsed;
    }
    ob_setting_status_t status =
        ob_servo_setting_set(cfg, setting, number, is_int, Py_TYPE(value)->tp_name, where, msg, sizeof(msg));
    if (status != OB_SETTING_OK) {
        PyErr_SetString(status == OB_SETTING_TYPE_ERROR ? PyExc_TypeError : PyExc_ValueError, msg);
        return -1;
    }
    return 0;
}

/* Apply keyword settings onto cfg, skipping the constructor's own arguments. */
static int apply_settings(ob_servo_config_t *cfg, PyObject *kwargs, const char *where, const char *const *skip) {
    if (kwargs == NULL) {
        return 0;
    }
    PyObject *key, *value;
    Py_ssize_t pos = 0;
    while (PyDict_Next(kwargs, &pos, &key, &value)) {
        const char *name = PyUnicode_AsUTF8(key);
        if (name == NULL) {
            return -1;
        }
        bool skipped = false;
        for (const char *const *s = skip; s != NULL && *s != NULL; s++) {
            skipped = skipped || strcmp(*s, name) == 0;
        }
        if (!skipped && set_one(cfg, name, value, where) < 0) {
            return -1;
        }
    }
    return 0;
}

static PyObject *settings_dict(const ob_servo_config_t *cfg) {
    PyObject *dict = PyDict_New();
    for (size_t i = 0; dict != NULL && i < OB_SERVO_SETTINGS_COUNT; i++) {
        const ob_servo_setting_t *setting = &ob_servo_settings[i];
        double number = ob_servo_setting_get(cfg, setting);
        PyObject *value = setting->is_ms ? PyLong_FromDouble(number) : PyFloat_FromDouble(number);
        if (value == NULL || PyDict_SetItemString(dict, setting->name, value) < 0) {
            Py_CLEAR(dict);
        }
        Py_XDECREF(value);
    }
    return dict;
}

/* ---- Construction. ---- */

static int callable_or_none(PyObject *obj, const char *name) {
    if (obj != NULL && obj != Py_None && !PyCallable_Check(obj)) {
        PyErr_Format(PyExc_TypeError, "Servo: %s must be callable, not %.100s", name, Py_TYPE(obj)->tp_name);
        return -1;
    }
    return 0;
}

static int servo_init(ServoObject *self, PyObject *args, PyObject *kwargs) {
    static const char *const io_names[] = {"read_angle", "write_duty", "write_coast", "duty_limit", "io", NULL};
    if (PyTuple_GET_SIZE(args) != 0) {
        PyErr_SetString(PyExc_TypeError,
                        "Servo() takes keyword arguments only: read_angle=, write_duty=, write_coast= and settings");
        return -1;
    }
    PyObject *read = NULL, *write = NULL, *coast = NULL, *duty_limit = NULL, *native = NULL;
    if (kwargs != NULL) {
        read = PyDict_GetItemString(kwargs, "read_angle");
        write = PyDict_GetItemString(kwargs, "write_duty");
        coast = PyDict_GetItemString(kwargs, "write_coast");
        duty_limit = PyDict_GetItemString(kwargs, "duty_limit");
        native = PyDict_GetItemString(kwargs, "io");
    }
    if (native == Py_None) {
        native = NULL;
    }
    if (read == Py_None) {
        read = NULL;
    }
    if (write == Py_None) {
        write = NULL;
    }
    if (coast == Py_None) {
        coast = NULL;
    }
    if (callable_or_none(read, "read_angle") < 0 || callable_or_none(write, "write_duty") < 0 ||
        callable_or_none(coast, "write_coast") < 0) {
        return -1;
    }
    int given = (read != NULL) + (write != NULL) + (coast != NULL);
    if (native != NULL) {
        if (given != 0) {
            PyErr_SetString(PyExc_TypeError,
                            "Servo: give either io= (a native motor IO) or the read_angle/write_duty/write_coast "
                            "callables, not both");
            return -1;
        }
        if (!ob_py_motor_io_check(native)) {
            PyErr_Format(PyExc_TypeError,
                         "Servo: io must be a native motor IO (an openbricks_native.MotorIO subclass such as "
                         "the simulator's wheel IO), not %.100s; pass Python functions as read_angle=, "
                         "write_duty= and write_coast= instead",
                         Py_TYPE(native)->tp_name);
            return -1;
        }
        if (!ob_py_motor_io_ready(native)) {
            PyErr_Format(PyExc_ValueError, "Servo: io=%.100s has no IO functions set (a bare MotorIO base object)",
                         Py_TYPE(native)->tp_name);
            return -1;
        }
    }
    if (given != 0 && given != 3) {
        PyErr_SetString(PyExc_TypeError,
                        "Servo: give all of read_angle, write_duty and write_coast (a motor that is ticked "
                        "by motor_process), or none of them (drive it with update())");
        return -1;
    }
    ob_servo_config_t cfg;
    ob_servo_config_default(&cfg);
    if (apply_settings(&cfg, kwargs, "Servo", io_names) < 0) {
        return -1;
    }
    float limit = 100.0f;
    if (duty_limit != NULL && duty_limit != Py_None) {
        if (ob_py_float(duty_limit, "Servo", "duty_limit", &limit) < 0) {
            return -1;
        }
        char msg[OB_SERVO_SETTING_MSG_SIZE];
        if (!ob_servo_duty_limit_valid(limit, "Servo", "duty_limit", "", msg, sizeof(msg))) {
            PyErr_SetString(PyExc_ValueError, msg);
            return -1;
        }
    }
    cfg.duty_limit_pct = limit;

    Py_XINCREF(read);
    Py_XINCREF(write);
    Py_XINCREF(coast);
    Py_XINCREF(native);
    Py_XSETREF(self->read_angle, read);
    Py_XSETREF(self->write_duty, write);
    Py_XSETREF(self->write_coast, coast);
    Py_XSETREF(self->native_io, native);

    ob_motor_io_t io;
    if (native != NULL) {
        /* The provider's functions never call Python: tick the core directly. */
        io = ((ob_py_motor_io_t *)native)->io;
        self->base.tick_fn = ob_servo_tick;
        self->base.tick_ctx = &self->servo;
    } else if (given == 3) {
        io = (ob_motor_io_t){py_read_angle, py_write_duty, py_write_coast, self};
        self->base.tick_fn = servo_tick_fn;
        self->base.tick_ctx = self;
    } else {
        io = ob_servo_direct_io;
        self->base.tick_fn = NULL;
        self->base.tick_ctx = NULL;
    }
    ob_servo_init(&self->servo, &io, &cfg);
    return 0;
}

static int servo_traverse(ServoObject *self, visitproc visit, void *arg) {
    Py_VISIT(self->read_angle);
    Py_VISIT(self->native_io);
    Py_VISIT(self->write_duty);
    Py_VISIT(self->write_coast);
    Py_VISIT(self->error_type);
    Py_VISIT(self->error_value);
    Py_VISIT(self->error_tb);
    return 0;
}

static int servo_clear(ServoObject *self) {
    /* Without its callables the servo can no longer be ticked. */
    self->base.tick_fn = NULL;
    self->servo.io = ob_servo_direct_io;
    Py_CLEAR(self->read_angle);
    Py_CLEAR(self->native_io);
    Py_CLEAR(self->write_duty);
    Py_CLEAR(self->write_coast);
    Py_CLEAR(self->error_type);
    Py_CLEAR(self->error_value);
    Py_CLEAR(self->error_tb);
    return 0;
}

static void servo_dealloc(ServoObject *self) {
    PyObject_GC_UnTrack(self);
    servo_clear(self);
    Py_TYPE(self)->tp_free((PyObject *)self);
}

static PyObject *servo_new(PyTypeObject *type, PyObject *args, PyObject *kwargs) {
    (void)args;
    (void)kwargs;
    ServoObject *self = (ServoObject *)type->tp_alloc(type, 0);
    if (self != NULL) {
        /* A usable direct-path servo even if __init__ is bypassed. */
        ob_servo_config_t cfg;
        ob_servo_config_default(&cfg);
        ob_servo_init(&self->servo, &ob_servo_direct_io, &cfg);
    }
    return (PyObject *)self;
}

/* ---- Commands. Each may write to the motor at once (dc, brake, coast). ---- */

static PyObject *done_or_raise(ServoObject *self) {
    if (raise_stashed(self) < 0) {
        return NULL;
    }
    Py_RETURN_NONE;
}

static PyObject *servo_run_speed(ServoObject *self, PyObject *arg) {
    float speed;
    if (ob_py_float(arg, "Servo.run_speed", "speed_dps", &speed) < 0) {
        return NULL;
    }
    ob_servo_run_speed(&self->servo, speed);
    return done_or_raise(self);
}

/* run_target and run_angle share their arguments. */
static PyObject *servo_move(ServoObject *self, PyObject *args, PyObject *kwargs, bool relative) {
    static char *kwlist_target[] = {"speed_dps", "target_deg", "then", "accel_dps2", "decel_dps2", NULL};
    static char *kwlist_angle[] = {"speed_dps", "angle_deg", "then", "accel_dps2", "decel_dps2", NULL};
    const char *where = relative ? "Servo.run_angle" : "Servo.run_target";
    PyObject *speed_obj, *value_obj, *then_obj = NULL, *accel_obj = Py_None, *decel_obj = Py_None;
    if (!PyArg_ParseTupleAndKeywords(args, kwargs, relative ? "OO|OOO:run_angle" : "OO|OOO:run_target",
                                     relative ? kwlist_angle : kwlist_target, &speed_obj, &value_obj,
                                     &then_obj, &accel_obj, &decel_obj)) {
        return NULL;
    }
    float speed, value;
    float accel = self->servo.cfg.accel_dps2, decel = self->servo.cfg.decel_dps2;
    ob_then_t then = OB_THEN_HOLD;
    if (ob_py_float(speed_obj, where, "speed_dps", &speed) < 0 ||
        ob_py_float(value_obj, where, relative ? "angle_deg" : "target_deg", &value) < 0 ||
        (then_obj != NULL && ob_py_then(then_obj, where, &then) < 0) ||
        (accel_obj != Py_None && ob_py_positive_float(accel_obj, where, "accel_dps2", &accel) < 0)) {
        return NULL;
    }
    if (decel_obj != Py_None) {
        if (ob_py_positive_float(decel_obj, where, "decel_dps2", &decel) < 0) {
            return NULL;
        }
    } else if (accel_obj != Py_None) {
        decel = accel; /* one rate given: use it both ways, like the manual's accel_dps2 */
    }
    if (speed == 0.0f) {
        PyErr_Format(PyExc_ValueError, "%s: speed_dps must not be 0 (use hold() to stay in place)", where);
        return NULL;
    }
    ob_servo_move(&self->servo, speed, value, relative, then, accel, decel);
    return done_or_raise(self);
}

static PyObject *servo_run_target(ServoObject *self, PyObject *args, PyObject *kwargs) {
    return servo_move(self, args, kwargs, false);
}

static PyObject *servo_run_angle(ServoObject *self, PyObject *args, PyObject *kwargs) {
    return servo_move(self, args, kwargs, true);
}

static PyObject *servo_hold(ServoObject *self, PyObject *unused) {
    (void)unused;
    ob_servo_hold(&self->servo);
    return done_or_raise(self);
}

static PyObject *servo_dc(ServoObject *self, PyObject *arg) {
    float duty;
    if (ob_py_float(arg, "Servo.dc", "duty_pct", &duty) < 0) {
        return NULL;
    }
    if (duty < -100.0f || duty > 100.0f) {
        PyErr_Format(PyExc_ValueError, "Servo.dc: duty_pct must be within -100..100, got %R", arg);
        return NULL;
    }
    ob_servo_dc(&self->servo, duty);
    return done_or_raise(self);
}

static PyObject *servo_brake(ServoObject *self, PyObject *unused) {
    (void)unused;
    ob_servo_brake(&self->servo);
    return done_or_raise(self);
}

static PyObject *servo_coast(ServoObject *self, PyObject *unused) {
    (void)unused;
    ob_servo_coast(&self->servo);
    return done_or_raise(self);
}

static PyObject *servo_stop(ServoObject *self, PyObject *args, PyObject *kwargs) {
    static char *kwlist[] = {"then", NULL};
    PyObject *then_obj = NULL;
    if (!PyArg_ParseTupleAndKeywords(args, kwargs, "|O:stop", kwlist, &then_obj)) {
        return NULL;
    }
    ob_then_t then = OB_THEN_COAST;
    if (then_obj != NULL && ob_py_then(then_obj, "Servo.stop", &then) < 0) {
        return NULL;
    }
    ob_servo_stop(&self->servo, then);
    return done_or_raise(self);
}

static PyObject *servo_reset_angle(ServoObject *self, PyObject *args, PyObject *kwargs) {
    static char *kwlist[] = {"angle_deg", NULL};
    PyObject *angle_obj = NULL;
    if (!PyArg_ParseTupleAndKeywords(args, kwargs, "|O:reset_angle", kwlist, &angle_obj)) {
        return NULL;
    }
    float angle = 0.0f;
    if (angle_obj != NULL && ob_py_float(angle_obj, "Servo.reset_angle", "angle_deg", &angle) < 0) {
        return NULL;
    }
    ob_servo_reset_angle(&self->servo, angle);
    Py_RETURN_NONE;
}

static PyObject *servo_set_duty_limit(ServoObject *self, PyObject *arg) {
    float limit = 100.0f;
    if (arg != Py_None) {
        if (ob_py_float(arg, "Servo.set_duty_limit", "limit_pct", &limit) < 0) {
            return NULL;
        }
        char msg[OB_SERVO_SETTING_MSG_SIZE];
        if (!ob_servo_duty_limit_valid(limit, "Servo.set_duty_limit", "limit_pct", " (None lifts it)", msg,
                                       sizeof(msg))) {
            PyErr_SetString(PyExc_ValueError, msg);
            return NULL;
        }
    }
    ob_servo_set_duty_limit(&self->servo, limit);
    Py_RETURN_NONE;
}

/* ---- Ticking. ---- */

static PyObject *duty_result(const ob_servo_t *s) {
    float duty;
    if (!ob_servo_duty_out(s, &duty)) {
        Py_RETURN_NONE;
    }
    return PyFloat_FromDouble((double)duty);
}

static PyObject *servo_tick(ServoObject *self, PyObject *arg) {
    uint32_t now_ms;
    if (ob_py_time_ms(arg, "Servo.tick", &now_ms) < 0) {
        return NULL;
    }
    if (self->read_angle == NULL && self->native_io == NULL) {
        PyErr_SetString(PyExc_TypeError,
                        "Servo.tick: this Servo has no read_angle/write_duty/write_coast callables or io; "
                        "use update(now_ms, measured_deg)");
        return NULL;
    }
    ob_servo_tick(&self->servo, now_ms);
    return done_or_raise(self);
}

static PyObject *servo_update(ServoObject *self, PyObject *const *args, Py_ssize_t nargs) {
    static const char *where = "Servo.update";
    if (nargs != 2) {
        PyErr_Format(PyExc_TypeError, "%s(now_ms, measured_deg) takes 2 arguments, got %zd", where, nargs);
        return NULL;
    }
    uint32_t now_ms;
    if (ob_py_time_ms(args[0], where, &now_ms) < 0) {
        return NULL;
    }
    float measured = 0.0f;
    bool have = args[1] != Py_None;
    if (have) {
        /* Exact floats skip the generic checks: this is the simulator's per-step call. */
        if (PyFloat_CheckExact(args[1])) {
            double value = PyFloat_AS_DOUBLE(args[1]);
            if (!isfinite(value) || fabs(value) > 3.0e38) {
                PyErr_Format(PyExc_ValueError, "%s: measured_deg must be a finite number, got %R", where, args[1]);
                return NULL;
            }
            measured = (float)value;
        } else if (ob_py_float(args[1], where, "measured_deg", &measured) < 0) {
            return NULL;
        }
    }
    ob_servo_step(&self->servo, now_ms, have, measured);
    if (raise_stashed(self) < 0) {
        return NULL;
    }
    return duty_result(&self->servo);
}

/* ---- Queries. ---- */

static PyObject *servo_angle(ServoObject *self, PyObject *unused) {
    (void)unused;
    return PyFloat_FromDouble((double)ob_servo_angle_deg(&self->servo));
}

static PyObject *servo_speed(ServoObject *self, PyObject *unused) {
    (void)unused;
    return PyFloat_FromDouble((double)ob_servo_speed_dps(&self->servo));
}

static PyObject *servo_done(ServoObject *self, PyObject *unused) {
    (void)unused;
    return PyBool_FromLong(ob_servo_is_done(&self->servo));
}

static PyObject *servo_stalled(ServoObject *self, PyObject *unused) {
    (void)unused;
    return PyBool_FromLong(ob_servo_is_stalled(&self->servo));
}

static PyObject *servo_settings(ServoObject *self, PyObject *args, PyObject *kwargs) {
    if (PyTuple_GET_SIZE(args) != 0) {
        PyErr_SetString(PyExc_TypeError, "Servo.settings() takes keyword arguments only");
        return NULL;
    }
    if (kwargs != NULL && PyDict_Size(kwargs) > 0) {
        ob_servo_config_t cfg = self->servo.cfg;
        if (apply_settings(&cfg, kwargs, "Servo.settings", NULL) < 0) {
            return NULL;
        }
        ob_servo_configure(&self->servo, &cfg);
    }
    return settings_dict(&self->servo.cfg);
}

static PyObject *servo_state(ServoObject *self, PyObject *unused) {
    (void)unused;
    const ob_servo_t *s = &self->servo;
    PyObject *duty = duty_result(s);
    if (duty == NULL) {
        return NULL;
    }
    PyObject *state = Py_BuildValue(
        "{s:s,s:s,s:O,s:O,s:O,s:k,s:k,s:d,s:d,s:N,s:d,s:d,s:d,s:d,s:k}", "mode", ob_servo_mode_name(s->mode), "then",
        ob_py_then_name(s->then), "done", s->done ? Py_True : Py_False, "stalled", s->stalled ? Py_True : Py_False,
        "feedback_lost", s->feedback_lost ? Py_True : Py_False, "failed_reads", (unsigned long)s->failed_reads,
        "silent_reads", (unsigned long)s->silent_ticks,
        "angle_deg", (double)s->angle_deg, "speed_dps", (double)s->observer.v_dps, "duty_pct", duty,
        "duty_limit_pct", (double)s->duty_limit_pct, "ref_x_deg", (double)(s->ref.x_deg + s->ref_offset_deg),
        "ref_v_dps", (double)s->ref.v_dps, "ref_a_dps2", (double)s->ref.a_dps2, "now_ms", (unsigned long)s->now_ms);
    return state;
}

static PyObject *get_failed_reads(ServoObject *self, void *closure) {
    (void)closure;
    return PyLong_FromUnsignedLong(self->servo.failed_reads);
}

static PyObject *get_feedback_lost(ServoObject *self, void *closure) {
    (void)closure;
    return PyBool_FromLong(self->servo.feedback_lost);
}

static PyObject *get_duty(ServoObject *self, void *closure) {
    (void)closure;
    return duty_result(&self->servo);
}

static PyObject *get_duty_limit(ServoObject *self, void *closure) {
    (void)closure;
    return PyFloat_FromDouble((double)self->servo.duty_limit_pct);
}

static PyMethodDef servo_methods[] = {
    {"run_speed", (PyCFunction)servo_run_speed, METH_O,
     "run_speed(speed_dps): ramp to speed_dps at accel_dps2 and keep it (closed loop). Never done()."},
    {"run_target", (PyCFunction)(void (*)(void))servo_run_target, METH_VARARGS | METH_KEYWORDS,
     "run_target(speed_dps, target_deg, then='hold', accel_dps2=None, decel_dps2=None): move to the absolute "
     "target_deg at up to |speed_dps|, then coast/stop, brake, hold or continue."},
    {"run_angle", (PyCFunction)(void (*)(void))servo_run_angle, METH_VARARGS | METH_KEYWORDS,
     "run_angle(speed_dps, angle_deg, then='hold', accel_dps2=None, decel_dps2=None): move by angle_deg; the "
     "direction is sign(speed_dps) * sign(angle_deg). Chained moves add up exactly."},
    {"hold", (PyCFunction)servo_hold, METH_NOARGS, "Stop and hold the current angle (closed loop)."},
    {"dc", (PyCFunction)servo_dc, METH_O, "dc(duty_pct): open-loop duty, -100..100 (capped by the duty limit)."},
    {"brake", (PyCFunction)servo_brake, METH_NOARGS, "Duty 0: the bridge shorts the motor."},
    {"coast", (PyCFunction)servo_coast, METH_NOARGS, "Release the motor."},
    {"stop", (PyCFunction)(void (*)(void))servo_stop, METH_VARARGS | METH_KEYWORDS,
     "stop(then='coast'): coast/stop, brake or hold now ('continue' coasts)."},
    {"reset_angle", (PyCFunction)(void (*)(void))servo_reset_angle, METH_VARARGS | METH_KEYWORDS,
     "reset_angle(angle_deg=0.0): the angle now reads angle_deg; a move or hold in progress shifts with it."},
    {"set_duty_limit", (PyCFunction)servo_set_duty_limit, METH_O,
     "set_duty_limit(limit_pct): cap |duty| (0 < limit <= 100; None lifts the cap). run_until_stalled's "
     "duty_limit: stall detection scales with the cap."},
    {"tick", (PyCFunction)servo_tick, METH_O,
     "tick(now_ms): one control step through the IO callables (what motor_process does)."},
    {"update", (PyCFunction)(void (*)(void))servo_update, METH_FASTCALL,
     "update(now_ms, measured_deg) -> duty_pct, or None while coasting: one control step with the angle "
     "given (None = no fresh reading), no callables involved."},
    {"angle", (PyCFunction)servo_angle, METH_NOARGS, "Last measured angle (degrees, reset_angle frame)."},
    {"speed", (PyCFunction)servo_speed, METH_NOARGS, "Estimated speed (deg/s)."},
    {"done", (PyCFunction)servo_done, METH_NOARGS,
     "True when no closed-loop move is in flight, or the move ended (on target, or stalled at its end)."},
    {"is_done", (PyCFunction)servo_done, METH_NOARGS, "Alias of done()."},
    {"stalled", (PyCFunction)servo_stalled, METH_NOARGS,
     "True when the motor has pushed (duty at its limit, or far behind its reference) while nearly still "
     "for stall_time_ms."},
    {"settings", (PyCFunction)(void (*)(void))servo_settings, METH_VARARGS | METH_KEYWORDS,
     "settings(**values) -> dict of every setting; with keywords, change those first."},
    {"state", (PyCFunction)servo_state, METH_NOARGS, "Snapshot of the controller for logs and tests."},
    {NULL, NULL, 0, NULL},
};

static PyGetSetDef servo_getset[] = {
    {"failed_reads", (getter)get_failed_reads, NULL, "Angle reads that failed since construction.", NULL},
    {"feedback_lost", (getter)get_feedback_lost, NULL,
     "True after a closed-loop command was halted because the angle went silent (until the next command).",
     NULL},
    {"duty", (getter)get_duty, NULL, "Duty written last, or None while coasting.", NULL},
    {"duty_limit", (getter)get_duty_limit, NULL, "Active duty cap in percent.", NULL},
    {NULL, NULL, NULL, NULL, NULL},
};

static PyTypeObject ServoType = {
    PyVarObject_HEAD_INIT(NULL, 0)
    .tp_name = "openbricks_native.Servo",
    .tp_basicsize = sizeof(ServoObject),
    .tp_flags = Py_TPFLAGS_DEFAULT | Py_TPFLAGS_HAVE_GC,
    .tp_doc = "Servo(*, read_angle=None, write_duty=None, write_coast=None, io=None, duty_limit=None, "
              "**settings)\n\n"
              "Closed-loop control of one motor with an angle sensor: speed runs, position moves and hold on "
              "trapezoidal trajectories, dc, brake, coast, stall detection, and a halt when the angle goes "
              "silent. With IO callables or a native io, subscribe it to motor_process; without, call "
              "update(). See settings() for the gains and limits (their defaults suit an ST-3032-class geared "
              "motor).",
    .tp_new = servo_new,
    .tp_init = (initproc)servo_init,
    .tp_dealloc = (destructor)servo_dealloc,
    .tp_traverse = (traverseproc)servo_traverse,
    .tp_clear = (inquiry)servo_clear,
    .tp_methods = servo_methods,
    .tp_getset = servo_getset,
};

int ob_py_add_servo(PyObject *module) {
    ServoType.tp_base = &ob_py_subscriber_type;
    if (PyType_Ready(&ServoType) < 0) {
        return -1;
    }
    Py_INCREF(&ServoType);
    if (PyModule_AddObject(module, "Servo", (PyObject *)&ServoType) < 0) {
        Py_DECREF(&ServoType);
        return -1;
    }
    return 0;
}
