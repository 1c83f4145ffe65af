/*
 * openbricks_native.DriveBase: the drivebase core for the host.
 *
 * Two ways to connect it to wheels:
 *   - IO callables (read_left/right() -> float degrees or None when there is
 *     no fresh reading, write_left/right(duty_pct), coast_left/right()): the
 *     object is then a native motor_process subscriber, and tick(now_ms)
 *     runs one period through them;
 *   - native IO (left_io=, right_io=: MotorIO-derived objects, py_motor_io.h,
 *     e.g. the simulator's wheels): a native subscriber too, with no Python
 *     call per tick;
 *   - no callables: the caller owns the loop and calls
 *     update(now_ms, left_deg, right_deg[, heading_deg]) -> (left, right),
 *     each a duty percent or None for a released (coasting) wheel. This path
 *     makes no Python calls at all.
 */
#include <float.h>
#include <math.h>

#include "bindings.h"
#include "drivebase.h"
#include "py_motor_io.h"
#include "py_subscriber.h"

typedef struct DriveBaseObject DriveBaseObject;

/* What an IO callback's ctx points at: the owner and which wheel. */
typedef struct {
    DriveBaseObject *owner;
    int side;
} ob_py_wheel_slot_t;

struct DriveBaseObject {
    ob_py_subscriber_t base;
    ob_drivebase_t db;
    ob_py_wheel_slot_t slots[2];
    PyObject *read[2];
    PyObject *write[2];
    PyObject *coast[2];
    PyObject *heading; /* heading source (IO mode): a callable, a native IMU, or NULL */
    ob_heading_source_t native_heading; /* read_heading set when `heading` is a native IMU */
    PyObject *native_io[2]; /* MotorIO providers (left_io=, right_io=), or NULL */
    /* First error an IO callable raised during the current period, re-raised when it ends. */
    PyObject *error_type, *error_value, *error_tb;
};

/* ---- then= ---------------------------------------------------------------------------------- */

static int parse_then(PyObject *obj, ob_then_t *then) {
    static const struct {
        const char *name;
        ob_then_t value;
    } names[] = {
        {"coast", OB_THEN_COAST}, {"stop", OB_THEN_COAST},         {"brake", OB_THEN_BRAKE},
        {"hold", OB_THEN_HOLD},   {"continue", OB_THEN_CONTINUE},
    };
    if (obj == NULL) {
        *then = OB_THEN_COAST;
        return 0;
    }
    if (PyUnicode_Check(obj)) {
        const char *s = PyUnicode_AsUTF8(obj);
        if (s == NULL) {
            return -1;
        }
        for (size_t i = 0; i < sizeof(names) / sizeof(names[0]); i++) {
            if (strcmp(s, names[i].name) == 0) {
                *then = names[i].value;
                return 0;
            }
        }
    }
    PyErr_Format(PyExc_ValueError,
                 "then must be one of 'coast' (or 'stop'), 'brake', 'hold', 'continue'; got %R", obj);
    return -1;
}

/* ---- argument checks ------------------------------------------------------------------------ */

static int finite_arg(PyObject *obj, const char *what, float *out) {
    double v = PyFloat_AsDouble(obj);
    if (v == -1.0 && PyErr_Occurred()) {
        PyErr_Format(PyExc_TypeError, "%s must be a number, got %R", what, obj);
        return -1;
    }
    if (!isfinite(v)) {
        PyErr_Format(PyExc_ValueError, "%s must be a finite number, got %R", what, obj);
        return -1;
    }
    if (fabs(v) > FLT_MAX) {
        PyErr_Format(PyExc_ValueError, "%s is beyond the float range of the controller (|x| <= 3.4e38), got %R",
                     what, obj);
        return -1;
    }
    *out = (float)v;
    return 0;
}

/* The core refuses a command whose wheel-degrees overflow float (a distance of 1e38 mm): say so. */
static PyObject *done_or_refused(bool accepted, const char *what) {
    if (!accepted) {
        PyErr_Format(PyExc_ValueError,
                     "%s: the values are too large for the drive base (its wheel-degrees overflow float); "
                     "nothing was changed",
                     what);
        return NULL;
    }
    Py_RETURN_NONE;
}

static int positive_arg(PyObject *obj, const char *what, const char *unit, float *out) {
    if (finite_arg(obj, what, out) < 0) {
        return -1;
    }
    if (!(*out > 0.0f)) {
        PyErr_Format(PyExc_ValueError, "%s must be > 0 %s, got %R", what, unit, obj);
        return -1;
    }
    return 0;
}

/* ---- IO callables --------------------------------------------------------------------------- */

/*
 * A callable that raises must not stop the period: the other wheel's IO still
 * runs (above all a halt's coast must reach both motors). So the first error
 * is stashed and re-raised when the period ends, later ones are dropped, and
 * a read that raised counts as a missing reading, which the watchdog handles.
 */
static void stash_error(DriveBaseObject *self) {
    if (self->error_type == NULL) {
        PyErr_Fetch(&self->error_type, &self->error_value, &self->error_tb);
    } else {
        PyErr_Clear();
    }
}

/* Re-raise the stashed error, if any: returns -1 with it set. */
static int raise_stashed(DriveBaseObject *self) {
    if (self->error_type == NULL) {
        return 0;
    }
    PyErr_Restore(self->error_type, self->error_value, self->error_tb);
    self->error_type = self->error_value = self->error_tb = NULL;
    return -1;
}

/* An angle from a callable's result: a number, or None for "no fresh reading". */
static bool angle_result(DriveBaseObject *self, PyObject *r, const char *what, float *out) {
    if (r == NULL) {
        stash_error(self);
        return false;
    }
    bool ok = false;
    if (r != Py_None) {
        double v = PyFloat_AsDouble(r);
        if (v == -1.0 && PyErr_Occurred()) {
            PyErr_Format(PyExc_TypeError, "%s must return degrees as a number or None, got %R", what, r);
            stash_error(self);
        } else {
            *out = (float)v;
            ok = isfinite(v);
        }
    }
    Py_DECREF(r);
    return ok;
}

static bool py_read_angle(void *ctx, float *angle_deg) {
    ob_py_wheel_slot_t *slot = ctx;
    PyObject *r = PyObject_CallNoArgs(slot->owner->read[slot->side]);
    return angle_result(slot->owner, r, slot->side == OB_DB_LEFT ? "read_left()" : "read_right()", angle_deg);
}

static void py_write_duty(void *ctx, float duty_pct) {
    ob_py_wheel_slot_t *slot = ctx;
    PyObject *arg = PyFloat_FromDouble(duty_pct);
    PyObject *r = arg == NULL ? NULL : PyObject_CallOneArg(slot->owner->write[slot->side], arg);
    Py_XDECREF(arg);
    if (r == NULL) {
        stash_error(slot->owner);
    }
    Py_XDECREF(r);
}

static void py_write_coast(void *ctx) {
    ob_py_wheel_slot_t *slot = ctx;
    PyObject *r = PyObject_CallNoArgs(slot->owner->coast[slot->side]);
    if (r == NULL) {
        stash_error(slot->owner);
    }
    Py_XDECREF(r);
}

static bool py_read_heading(void *ctx, float *heading_deg) {
    DriveBaseObject *self = ctx;
    if (self->heading == NULL) {
        return false;
    }
    return angle_result(self, PyObject_CallNoArgs(self->heading), "heading()", heading_deg);
}

/* motor_process's native entry: one period through the IO callables. */
static void py_drivebase_tick(void *ctx, uint32_t now_ms) {
    DriveBaseObject *self = ctx;
    ob_drivebase_tick(&self->db, now_ms);
    raise_stashed(self);
}

static bool has_io(const DriveBaseObject *self) {
    return self->read[0] != NULL || self->native_io[0] != NULL;
}

/* ---- type ----------------------------------------------------------------------------------- */

static int DriveBase_traverse(DriveBaseObject *self, visitproc visit, void *arg) {
    for (int i = 0; i < 2; i++) {
        Py_VISIT(self->read[i]);
        Py_VISIT(self->write[i]);
        Py_VISIT(self->coast[i]);
        Py_VISIT(self->native_io[i]);
    }
    Py_VISIT(self->heading);
    return 0;
}

static int DriveBase_clear(DriveBaseObject *self) {
    self->base.tick_fn = NULL;
    for (int i = 0; i < 2; i++) {
        Py_CLEAR(self->read[i]);
        Py_CLEAR(self->write[i]);
        Py_CLEAR(self->coast[i]);
        Py_CLEAR(self->native_io[i]);
        self->db.io[i].read_angle = NULL;
        self->db.io[i].write_duty = NULL;
        self->db.io[i].write_coast = NULL;
    }
    Py_CLEAR(self->heading);
    self->native_heading.read_heading = NULL;
    self->native_heading.ctx = NULL;
    Py_CLEAR(self->error_type);
    Py_CLEAR(self->error_value);
    Py_CLEAR(self->error_tb);
    return 0;
}

static void DriveBase_dealloc(DriveBaseObject *self) {
    PyObject_GC_UnTrack(self);
    DriveBase_clear(self);
    Py_TYPE(self)->tp_free((PyObject *)self);
}

static int DriveBase_init(DriveBaseObject *self, PyObject *args, PyObject *kwargs) {
    static char *kwlist[] = {"wheel_diameter_mm", "axle_track_mm", "read_left", "read_right", "write_left",
                             "write_right", "coast_left", "coast_right", "heading", "watchdog_ms",
                             "left_io", "right_io", NULL};
    PyObject *diameter_obj, *track_obj;
    PyObject *io[6] = {NULL, NULL, NULL, NULL, NULL, NULL};
    PyObject *native[2] = {NULL, NULL};
    PyObject *heading = NULL;
    unsigned int watchdog_ms = OB_DB_DEFAULT_WATCHDOG_MS;
    if (!PyArg_ParseTupleAndKeywords(args, kwargs, "OO|$OOOOOOOIOO:DriveBase", kwlist, &diameter_obj, &track_obj,
                                     &io[0], &io[1], &io[2], &io[3], &io[4], &io[5], &heading, &watchdog_ms,
                                     &native[0], &native[1])) {
        return -1;
    }
    float diameter_mm, track_mm;
    if (positive_arg(diameter_obj, "DriveBase(): wheel_diameter_mm", "mm", &diameter_mm) < 0 ||
        positive_arg(track_obj, "DriveBase(): axle_track_mm", "mm", &track_mm) < 0) {
        return -1;
    }
    if (watchdog_ms == 0) {
        PyErr_SetString(PyExc_ValueError, "DriveBase(): watchdog_ms must be >= 1 ms");
        return -1;
    }
    static const char *const io_names[6] = {"read_left",  "read_right",  "write_left",
                                            "write_right", "coast_left", "coast_right"};
    int given = 0;
    for (int i = 0; i < 6; i++) {
        if (io[i] == Py_None) {
            io[i] = NULL;
        }
        if (io[i] != NULL) {
            if (!PyCallable_Check(io[i])) {
                PyErr_Format(PyExc_TypeError, "DriveBase(): %s must be callable, got %R", io_names[i], io[i]);
                return -1;
            }
            given++;
        }
    }
    if (given != 0 && given != 6) {
        for (int i = 0; i < 6; i++) {
            if (io[i] == NULL) {
                PyErr_Format(PyExc_TypeError,
                             "DriveBase(): give all six IO callables (read_left, read_right, write_left, "
                             "write_right, coast_left, coast_right) or none (then drive it with update()); "
                             "%s is missing",
                             io_names[i]);
                return -1;
            }
        }
    }
    int native_given = 0;
    for (int i = 0; i < 2; i++) {
        if (native[i] == Py_None) {
            native[i] = NULL;
        }
        if (native[i] == NULL) {
            continue;
        }
        native_given++;
        if (!ob_py_motor_io_check(native[i])) {
            PyErr_Format(PyExc_TypeError,
                         "DriveBase(): %s_io must be a native motor IO (an openbricks_native.MotorIO subclass "
                         "such as the simulator's wheel IO), got %R",
                         i == 0 ? "left" : "right", native[i]);
            return -1;
        }
        if (!ob_py_motor_io_ready(native[i])) {
            PyErr_Format(PyExc_ValueError, "DriveBase(): %s_io has no IO functions set (a bare MotorIO object)",
                         i == 0 ? "left" : "right");
            return -1;
        }
    }
    if (native_given == 1 || (native_given == 2 && given != 0)) {
        PyErr_SetString(PyExc_TypeError,
                        "DriveBase(): give both left_io and right_io (native wheel IO), or the six IO callables, "
                        "not a mix");
        return -1;
    }
    if (heading == Py_None) {
        heading = NULL;
    }
    ob_heading_source_t native_heading = {NULL, NULL};
    if (heading != NULL && !ob_py_icm45686_heading_source(heading, &native_heading) && !PyCallable_Check(heading)) {
        PyErr_Format(PyExc_TypeError,
                     "DriveBase(): heading must be a callable returning degrees or a native IMU "
                     "(openbricks_native.ICM45686), got %R",
                     heading);
        return -1;
    }

    DriveBase_clear(self);
    ob_motor_io_t wheel_io[2] = {{0}, {0}};
    if (given == 6) {
        for (int i = 0; i < 2; i++) {
            self->slots[i].owner = self;
            self->slots[i].side = i;
            self->read[i] = Py_NewRef(io[i]);
            self->write[i] = Py_NewRef(io[2 + i]);
            self->coast[i] = Py_NewRef(io[4 + i]);
            wheel_io[i].read_angle = py_read_angle;
            wheel_io[i].write_duty = py_write_duty;
            wheel_io[i].write_coast = py_write_coast;
            wheel_io[i].ctx = &self->slots[i];
        }
    }
    if (native_given == 2) {
        for (int i = 0; i < 2; i++) {
            self->native_io[i] = Py_NewRef(native[i]);
            wheel_io[i] = ((ob_py_motor_io_t *)native[i])->io;
        }
    }
    self->heading = Py_XNewRef(heading);
    self->native_heading = native_heading;
    ob_drivebase_init(&self->db, &wheel_io[0], &wheel_io[1], diameter_mm, track_mm);
    self->db.watchdog_ms = watchdog_ms;
    if (given == 6 || native_given == 2) {
        self->base.tick_fn = py_drivebase_tick;
        self->base.tick_ctx = self;
    }
    return 0;
}

/* ---- commands ------------------------------------------------------------------------------- */

static PyObject *DriveBase_settings(DriveBaseObject *self, PyObject *args, PyObject *kwargs) {
    static char *kwlist[] = {"straight_speed", "turn_rate", "acceleration", "turn_acceleration", NULL};
    PyObject *objs[4] = {NULL, NULL, NULL, NULL};
    if (!PyArg_ParseTupleAndKeywords(args, kwargs, "|OOOO:settings", kwlist, &objs[0], &objs[1], &objs[2],
                                     &objs[3])) {
        return NULL;
    }
    float values[4] = {self->db.straight_speed_dps, self->db.turn_rate_dps, self->db.acceleration_dps2,
                       self->db.turn_acceleration_dps2};
    static const char *const units[4] = {"wheel-deg/s", "wheel-deg/s", "wheel-deg/s^2", "wheel-deg/s^2"};
    bool any = false;
    for (int i = 0; i < 4; i++) {
        if (objs[i] == NULL || objs[i] == Py_None) {
            continue;
        }
        char what[48];
        snprintf(what, sizeof(what), "settings(): %s", kwlist[i]);
        if (positive_arg(objs[i], what, units[i], &values[i]) < 0) {
            return NULL;
        }
        any = true;
    }
    if (!any) {
        return Py_BuildValue("(ffff)", values[0], values[1], values[2], values[3]);
    }
    ob_drivebase_settings(&self->db, values[0], values[1], values[2], values[3]);
    Py_RETURN_NONE;
}

static PyObject *DriveBase_straight(DriveBaseObject *self, PyObject *args, PyObject *kwargs) {
    static char *kwlist[] = {"distance_mm", "then", NULL};
    PyObject *distance_obj, *then_obj = NULL;
    if (!PyArg_ParseTupleAndKeywords(args, kwargs, "O|O:straight", kwlist, &distance_obj, &then_obj)) {
        return NULL;
    }
    float distance_mm;
    ob_then_t then;
    if (finite_arg(distance_obj, "straight(): distance_mm", &distance_mm) < 0 || parse_then(then_obj, &then) < 0) {
        return NULL;
    }
    return done_or_refused(ob_drivebase_straight(&self->db, distance_mm, then), "straight()");
}

static PyObject *DriveBase_turn(DriveBaseObject *self, PyObject *args, PyObject *kwargs) {
    static char *kwlist[] = {"angle_deg", "then", NULL};
    PyObject *angle_obj, *then_obj = NULL;
    if (!PyArg_ParseTupleAndKeywords(args, kwargs, "O|O:turn", kwlist, &angle_obj, &then_obj)) {
        return NULL;
    }
    float angle_deg;
    ob_then_t then;
    if (finite_arg(angle_obj, "turn(): angle_deg", &angle_deg) < 0 || parse_then(then_obj, &then) < 0) {
        return NULL;
    }
    return done_or_refused(ob_drivebase_turn(&self->db, angle_deg, then), "turn()");
}

static PyObject *DriveBase_curve(DriveBaseObject *self, PyObject *args, PyObject *kwargs) {
    static char *kwlist[] = {"radius", "angle", "then", NULL};
    PyObject *radius_obj, *angle_obj, *then_obj = NULL;
    if (!PyArg_ParseTupleAndKeywords(args, kwargs, "OO|O:curve", kwlist, &radius_obj, &angle_obj, &then_obj)) {
        return NULL;
    }
    float radius_mm, angle_deg;
    ob_then_t then;
    if (finite_arg(radius_obj, "curve(): radius (mm)", &radius_mm) < 0 ||
        finite_arg(angle_obj, "curve(): angle (deg)", &angle_deg) < 0 || parse_then(then_obj, &then) < 0) {
        return NULL;
    }
    return done_or_refused(ob_drivebase_curve(&self->db, radius_mm, angle_deg, then), "curve()");
}

static PyObject *DriveBase_drive(DriveBaseObject *self, PyObject *args, PyObject *kwargs) {
    static char *kwlist[] = {"speed_mm_s", "turn_rate_dps", NULL};
    PyObject *speed_obj, *rate_obj;
    if (!PyArg_ParseTupleAndKeywords(args, kwargs, "OO:drive", kwlist, &speed_obj, &rate_obj)) {
        return NULL;
    }
    float speed_mm_s, turn_rate_dps;
    if (finite_arg(speed_obj, "drive(): speed_mm_s", &speed_mm_s) < 0 ||
        finite_arg(rate_obj, "drive(): turn_rate_dps", &turn_rate_dps) < 0) {
        return NULL;
    }
    return done_or_refused(ob_drivebase_drive(&self->db, speed_mm_s, turn_rate_dps), "drive()");
}

static PyObject *DriveBase_move_wheels(DriveBaseObject *self, PyObject *args, PyObject *kwargs) {
    static char *kwlist[] = {"left_wheel_speed", "right_wheel_speed", NULL};
    PyObject *left_obj, *right_obj;
    if (!PyArg_ParseTupleAndKeywords(args, kwargs, "OO:move_wheels", kwlist, &left_obj, &right_obj)) {
        return NULL;
    }
    float left_dps, right_dps;
    if (finite_arg(left_obj, "move_wheels(): left_wheel_speed (wheel-deg/s)", &left_dps) < 0 ||
        finite_arg(right_obj, "move_wheels(): right_wheel_speed (wheel-deg/s)", &right_dps) < 0) {
        return NULL;
    }
    return done_or_refused(ob_drivebase_move_wheels(&self->db, left_dps, right_dps), "move_wheels()");
}

static PyObject *DriveBase_stop(DriveBaseObject *self, PyObject *args, PyObject *kwargs) {
    static char *kwlist[] = {"then", NULL};
    PyObject *then_obj = NULL;
    if (!PyArg_ParseTupleAndKeywords(args, kwargs, "|O:stop", kwlist, &then_obj)) {
        return NULL;
    }
    ob_then_t then;
    if (parse_then(then_obj, &then) < 0) {
        return NULL;
    }
    ob_drivebase_stop(&self->db, then);
    if (raise_stashed(self) < 0) {
        return NULL; /* a coast callable raised */
    }
    Py_RETURN_NONE;
}

static PyObject *DriveBase_reset(DriveBaseObject *self, PyObject *Py_UNUSED(ignored)) {
    if (!ob_drivebase_reset(&self->db)) {
        PyErr_SetString(PyExc_RuntimeError,
                        "DriveBase.reset() refused: a move is in progress; call stop() or wait for done() first");
        return NULL;
    }
    Py_RETURN_NONE;
}

static PyObject *DriveBase_use_gyro(DriveBaseObject *self, PyObject *arg) {
    int enable = PyObject_IsTrue(arg);
    if (enable < 0) {
        return NULL;
    }
    if (!enable) {
        ob_drivebase_use_gyro(&self->db, NULL);
        Py_RETURN_NONE;
    }
    if (has_io(self) && self->heading == NULL) {
        PyErr_SetString(PyExc_ValueError,
                        "use_gyro(True) needs a heading source: pass heading=<callable returning degrees, or a "
                        "native ICM45686> to DriveBase(...)");
        return NULL;
    }
    /* Without IO callables the heading arrives through update(..., heading_deg); a native IMU is read in C. */
    ob_heading_source_t source = {self->heading != NULL ? py_read_heading : NULL, self};
    if (self->native_heading.read_heading != NULL) {
        source = self->native_heading;
    }
    ob_drivebase_use_gyro(&self->db, &source);
    Py_RETURN_NONE;
}

/* The watchdog's fault as an OSError that says which feedback went silent and what to check. */
static PyObject *raise_fault(const DriveBaseObject *self) {
    uint8_t fault = ob_drivebase_fault(&self->db);
    const char *which = (fault & OB_DB_FAULT_LEFT) && (fault & OB_DB_FAULT_RIGHT) ? "both wheels"
                        : (fault & OB_DB_FAULT_LEFT)                              ? "the left wheel"
                        : (fault & OB_DB_FAULT_RIGHT)                             ? "the right wheel"
                                                                                  : "the gyro";
    PyErr_Format(PyExc_OSError,
                 "DriveBase halted: no reading from %s for more than %u ms, so both wheels were released "
                 "instead of chasing a frozen position. Check that motor's power and wiring (or the IMU's); "
                 "the next move retries.",
                 which, (unsigned)self->db.watchdog_ms);
    return NULL;
}

static PyObject *DriveBase_done(DriveBaseObject *self, PyObject *Py_UNUSED(ignored)) {
    if (ob_drivebase_fault(&self->db) != 0) {
        return raise_fault(self);
    }
    return PyBool_FromLong(ob_drivebase_done(&self->db));
}

static PyObject *DriveBase_fault(DriveBaseObject *self, PyObject *Py_UNUSED(ignored)) {
    uint8_t fault = ob_drivebase_fault(&self->db);
    if (fault == 0) {
        Py_RETURN_NONE;
    }
    PyObject *names = PyTuple_New(0);
    static const struct {
        uint8_t bit;
        const char *name;
    } bits[] = {{OB_DB_FAULT_LEFT, "left"}, {OB_DB_FAULT_RIGHT, "right"}, {OB_DB_FAULT_GYRO, "gyro"}};
    for (size_t i = 0; names != NULL && i < sizeof(bits) / sizeof(bits[0]); i++) {
        if (fault & bits[i].bit) {
            PyObject *name = PyUnicode_FromString(bits[i].name);
            Py_ssize_t n = PyTuple_GET_SIZE(names);
            if (name == NULL || _PyTuple_Resize(&names, n + 1) < 0) {
                Py_XDECREF(name);
                Py_XDECREF(names);
                return NULL;
            }
            PyTuple_SET_ITEM(names, n, name);
        }
    }
    return names;
}

static PyObject *DriveBase_state(DriveBaseObject *self, PyObject *Py_UNUSED(ignored)) {
    ob_drivebase_state_t st;
    ob_drivebase_get_state(&self->db, &st);
    return Py_BuildValue("(ffff)", st.distance_mm, st.drive_speed_mm_s, st.angle_deg, st.turn_rate_dps);
}

static PyObject *DriveBase_distance(DriveBaseObject *self, PyObject *Py_UNUSED(ignored)) {
    ob_drivebase_state_t st;
    ob_drivebase_get_state(&self->db, &st);
    return PyFloat_FromDouble(st.distance_mm);
}

static PyObject *DriveBase_angle(DriveBaseObject *self, PyObject *Py_UNUSED(ignored)) {
    ob_drivebase_state_t st;
    ob_drivebase_get_state(&self->db, &st);
    return PyFloat_FromDouble(st.angle_deg);
}

/* ---- control periods ------------------------------------------------------------------------ */

static int now_arg(PyObject *obj, uint32_t *now_ms) {
    unsigned long v = PyLong_AsUnsignedLongMask(obj); /* the scheduler clock wraps modulo 2^32 */
    if (v == (unsigned long)-1 && PyErr_Occurred()) {
        PyErr_Format(PyExc_TypeError, "now_ms must be an int (milliseconds), got %R", obj);
        return -1;
    }
    *now_ms = (uint32_t)v;
    return 0;
}

/* A reading for update(): a number, or None for "no fresh reading this period". */
static int reading_arg(PyObject *obj, const char *what, bool *ok, float *value) {
    if (PyFloat_CheckExact(obj)) {
        /* The simulator's per-step call: skip the generic conversion. */
        double v = PyFloat_AS_DOUBLE(obj);
        *ok = isfinite(v);
        *value = (float)v;
        return 0;
    }
    if (obj == Py_None) {
        *ok = false;
        *value = 0.0f;
        return 0;
    }
    double v = PyFloat_AsDouble(obj);
    if (v == -1.0 && PyErr_Occurred()) {
        PyErr_Format(PyExc_TypeError, "update(): %s must be degrees (a number) or None, got %R", what, obj);
        return -1;
    }
    *ok = isfinite(v);
    *value = (float)v;
    return 0;
}

static PyObject *duty_or_none(const ob_drivebase_output_t *out, int side) {
    if (out->coast[side]) {
        Py_RETURN_NONE;
    }
    return PyFloat_FromDouble(out->duty_pct[side]);
}

static PyObject *DriveBase_update(DriveBaseObject *self, PyObject *const *args, Py_ssize_t nargs) {
    if (nargs < 3 || nargs > 4) {
        PyErr_Format(PyExc_TypeError, "update(now_ms, left_deg, right_deg[, heading_deg]) takes 3 or 4 "
                                      "arguments, got %zd",
                     nargs);
        return NULL;
    }
    uint32_t now_ms;
    ob_drivebase_feedback_t fb;
    if (now_arg(args[0], &now_ms) < 0 ||
        reading_arg(args[1], "left_deg", &fb.wheel_ok[OB_DB_LEFT], &fb.wheel_deg[OB_DB_LEFT]) < 0 ||
        reading_arg(args[2], "right_deg", &fb.wheel_ok[OB_DB_RIGHT], &fb.wheel_deg[OB_DB_RIGHT]) < 0) {
        return NULL;
    }
    fb.heading_ok = false;
    fb.heading_deg = 0.0f;
    if (nargs == 4) {
        if (reading_arg(args[3], "heading_deg", &fb.heading_ok, &fb.heading_deg) < 0) {
            return NULL;
        }
    } else if (self->db.use_gyro) {
        PyErr_SetString(PyExc_TypeError, "update(): use_gyro(True) is on, so pass heading_deg "
                                         "(or None for a missed sample) as the fourth argument");
        return NULL;
    }
    ob_drivebase_output_t out;
    ob_drivebase_step(&self->db, now_ms, &fb, &out);
    PyObject *left = duty_or_none(&out, OB_DB_LEFT);
    PyObject *right = duty_or_none(&out, OB_DB_RIGHT);
    if (left == NULL || right == NULL) {
        Py_XDECREF(left);
        Py_XDECREF(right);
        return NULL;
    }
    PyObject *result = PyTuple_New(2);
    if (result == NULL) {
        Py_DECREF(left);
        Py_DECREF(right);
        return NULL;
    }
    PyTuple_SET_ITEM(result, 0, left);
    PyTuple_SET_ITEM(result, 1, right);
    return result;
}

static PyObject *DriveBase_tick(DriveBaseObject *self, PyObject *arg) {
    if (!has_io(self)) {
        PyErr_SetString(PyExc_ValueError, "tick() runs through the IO callables and this DriveBase has none; "
                                          "use update(now_ms, left_deg, right_deg) instead");
        return NULL;
    }
    uint32_t now_ms;
    if (now_arg(arg, &now_ms) < 0) {
        return NULL;
    }
    py_drivebase_tick(self, now_ms);
    if (PyErr_Occurred()) {
        return NULL;
    }
    Py_RETURN_NONE;
}

static PyMethodDef DriveBase_methods[] = {
    {"settings", (PyCFunction)(void (*)(void))DriveBase_settings, METH_VARARGS | METH_KEYWORDS,
     "settings(straight_speed=None, turn_rate=None, acceleration=None, turn_acceleration=None)\n"
     "Set cruise speeds (wheel-deg/s) and accelerations (wheel-deg/s^2); with no arguments, return them."},
    {"straight", (PyCFunction)(void (*)(void))DriveBase_straight, METH_VARARGS | METH_KEYWORDS,
     "straight(distance_mm, then='coast'): arm a straight move; poll done()."},
    {"turn", (PyCFunction)(void (*)(void))DriveBase_turn, METH_VARARGS | METH_KEYWORDS,
     "turn(angle_deg, then='coast'): arm a turn in place, positive = clockwise from above."},
    {"curve", (PyCFunction)(void (*)(void))DriveBase_curve, METH_VARARGS | METH_KEYWORDS,
     "curve(radius, angle, then='coast'): arm an arc; radius sign = travel direction, angle > 0 turns right."},
    {"drive", (PyCFunction)(void (*)(void))DriveBase_drive, METH_VARARGS | METH_KEYWORDS,
     "drive(speed_mm_s, turn_rate_dps): ramp to a forward speed and turn rate, and keep them."},
    {"move_wheels", (PyCFunction)(void (*)(void))DriveBase_move_wheels, METH_VARARGS | METH_KEYWORDS,
     "move_wheels(left_wheel_speed, right_wheel_speed): ramp each wheel to a speed in wheel-deg/s."},
    {"stop", (PyCFunction)(void (*)(void))DriveBase_stop, METH_VARARGS | METH_KEYWORDS,
     "stop(then='coast'): coast now, or decelerate at the acceleration setting and brake or hold."},
    {"reset", (PyCFunction)DriveBase_reset, METH_NOARGS,
     "reset(): the current pose becomes distance 0, heading 0 (encoders and gyro together)."},
    {"use_gyro", (PyCFunction)DriveBase_use_gyro, METH_O,
     "use_gyro(enable): steer by the heading source instead of the encoder difference."},
    {"done", (PyCFunction)DriveBase_done, METH_NOARGS,
     "done(): True when the last command reached its goal; OSError if the watchdog halted the drivebase."},
    {"fault", (PyCFunction)DriveBase_fault, METH_NOARGS,
     "fault(): None, or the silent feedback(s) that halted the drivebase, e.g. ('left',)."},
    {"state", (PyCFunction)DriveBase_state, METH_NOARGS,
     "state() -> (distance_mm, drive_speed_mm_s, angle_deg, turn_rate_dps)"},
    {"distance", (PyCFunction)DriveBase_distance, METH_NOARGS, "distance() -> mm since the last reset()."},
    {"angle", (PyCFunction)DriveBase_angle, METH_NOARGS, "angle() -> body degrees since the last reset()."},
    {"update", (PyCFunction)(void (*)(void))DriveBase_update, METH_FASTCALL,
     "update(now_ms, left_deg, right_deg[, heading_deg]) -> (left, right)\n"
     "One control period from readings (None = no fresh reading). Each output is a duty percent, "
     "or None for a released wheel."},
    {"tick", (PyCFunction)DriveBase_tick, METH_O,
     "tick(now_ms): one control period through the IO callables."},
    {NULL, NULL, 0, NULL},
};

static PyTypeObject DriveBaseType = {
    PyVarObject_HEAD_INIT(NULL, 0).tp_name = "openbricks_native.DriveBase",
    .tp_doc = PyDoc_STR("DriveBase(wheel_diameter_mm, axle_track_mm, *, read_left=None, read_right=None, "
                        "write_left=None, write_right=None, coast_left=None, coast_right=None, heading=None, "
                        "watchdog_ms=20, left_io=None, right_io=None)\n"
                        "Two-wheel drivebase with coupled (forward, heading) control."),
    .tp_basicsize = sizeof(DriveBaseObject),
    .tp_flags = Py_TPFLAGS_DEFAULT | Py_TPFLAGS_HAVE_GC,
    .tp_new = PyType_GenericNew,
    .tp_init = (initproc)DriveBase_init,
    .tp_dealloc = (destructor)DriveBase_dealloc,
    .tp_traverse = (traverseproc)DriveBase_traverse,
    .tp_clear = (inquiry)DriveBase_clear,
    .tp_free = PyObject_GC_Del,
    .tp_methods = DriveBase_methods,
};

int ob_py_add_drivebase(PyObject *module) {
    DriveBaseType.tp_base = &ob_py_subscriber_type;
    if (PyType_Ready(&DriveBaseType) < 0) {
        return -1;
    }
    return PyModule_AddObjectRef(module, "DriveBase", (PyObject *)&DriveBaseType);
}
