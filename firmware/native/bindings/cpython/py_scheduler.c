/*
 * motor_process: the scheduler core behind a Python object.
 *
 * Native subscribers (Servo, DriveBase: see py_subscriber.h) are ticked
 * through their C function pointer with no Python call; any other callable is
 * accepted too and called as callable(now_ms), the slow path the manual keeps
 * for user extensions.
 *
 * Each subscriber occupies a slot of this object, and the core registry holds
 * (dispatch, slot). dispatch runs the subscriber and catches a Python error
 * it leaves behind, so one failing subscriber cannot stop the others being
 * controlled in the same tick; tick() raises the first error afterwards.
 */
#include <stddef.h>

#include "bindings.h"
#include "py_args.h"
#include "py_capi.h"
#include "py_subscriber.h"
#include "scheduler.h"

/* ---- The Subscriber base type. ---- */

PyTypeObject ob_py_subscriber_type = {
    PyVarObject_HEAD_INIT(NULL, 0)
    .tp_name = "openbricks_native.Subscriber",
    .tp_basicsize = sizeof(ob_py_subscriber_t),
    .tp_flags = Py_TPFLAGS_DEFAULT | Py_TPFLAGS_BASETYPE,
    .tp_doc = "Base of the controllers that motor_process ticks natively (Servo, DriveBase).",
};

/* ---- MotorProcess. ---- */

typedef struct MotorProcessObject MotorProcessObject;

typedef struct {
    PyObject *obj; /* strong reference; NULL when the slot is free */
    ob_tick_fn_t fn;
    void *ctx;
    MotorProcessObject *owner;
} slot_t;

struct MotorProcessObject {
    PyObject_HEAD
    ob_scheduler_t sched;
    slot_t slots[OB_SCHEDULER_MAX_SUBSCRIBERS];
    PyObject *error_type; /* first error of the running tick, re-raised at its end */
    PyObject *error_value;
    PyObject *error_tb;
};

static void catch_error(MotorProcessObject *owner) {
    if (owner->error_type == NULL) {
        PyErr_Fetch(&owner->error_type, &owner->error_value, &owner->error_tb);
    } else {
        /* Only the first error of a tick is raised; later ones are reported, not lost silently. */
        PyErr_WriteUnraisable(NULL);
    }
}

static void dispatch(void *ctx, uint32_t now_ms) {
    slot_t *slot = (slot_t *)ctx;
    /* The subscriber may unsubscribe itself from Python during its tick: keep
     * it alive until the tick returns. */
    PyObject *obj = slot->obj;
    MotorProcessObject *owner = slot->owner;
    Py_INCREF(obj);
    slot->fn(slot->ctx, now_ms);
    if (PyErr_Occurred()) {
        catch_error(owner);
    }
    Py_DECREF(obj);
}

/* The slow path: a Python callable, called with the tick time. */
static void call_python(void *ctx, uint32_t now_ms) {
    PyObject *arg = PyLong_FromUnsignedLong(now_ms);
    if (arg == NULL) {
        return;
    }
    PyObject *result = PyObject_CallOneArg((PyObject *)ctx, arg);
    Py_DECREF(arg);
    Py_XDECREF(result);
}

static slot_t *find_slot(MotorProcessObject *self, PyObject *obj) {
    for (int i = 0; i < OB_SCHEDULER_MAX_SUBSCRIBERS; i++) {
        if (self->slots[i].obj == obj) {
            return &self->slots[i];
        }
    }
    return NULL;
}

static void release_slot(MotorProcessObject *self, slot_t *slot) {
    ob_scheduler_unsubscribe(&self->sched, dispatch, slot);
    PyObject *obj = slot->obj;
    slot->obj = NULL;
    slot->fn = NULL;
    slot->ctx = NULL;
    Py_XDECREF(obj);
}

static int mp_init(MotorProcessObject *self, PyObject *args, PyObject *kwargs) {
    if (!PyArg_ParseTuple(args, ":MotorProcess") || (kwargs != NULL && PyDict_Size(kwargs) > 0)) {
        if (!PyErr_Occurred()) {
            PyErr_SetString(PyExc_TypeError, "MotorProcess() takes no arguments");
        }
        return -1;
    }
    for (int i = 0; i < OB_SCHEDULER_MAX_SUBSCRIBERS; i++) {
        if (self->slots[i].obj != NULL) {
            release_slot(self, &self->slots[i]);
        }
        self->slots[i].owner = self;
    }
    ob_scheduler_init(&self->sched);
    return 0;
}

static PyObject *mp_subscribe(MotorProcessObject *self, PyObject *obj) {
    if (find_slot(self, obj) != NULL) {
        Py_RETURN_NONE; /* idempotent */
    }
    ob_tick_fn_t fn;
    void *ctx;
    if (ob_py_subscriber_check(obj)) {
        ob_py_subscriber_t *sub = (ob_py_subscriber_t *)obj;
        if (sub->tick_fn == NULL) {
            PyErr_Format(PyExc_ValueError,
                         "motor_process.subscribe: this %.100s has no IO to tick (it was built without "
                         "read/write callables); drive it with its update() method instead",
                         Py_TYPE(obj)->tp_name);
            return NULL;
        }
        fn = sub->tick_fn;
        ctx = sub->tick_ctx;
    } else if (PyCallable_Check(obj)) {
        fn = call_python;
        ctx = obj;
    } else {
        PyErr_Format(PyExc_TypeError,
                     "motor_process.subscribe: expected a Servo, a DriveBase or a callable taking now_ms, "
                     "not %.100s",
                     Py_TYPE(obj)->tp_name);
        return NULL;
    }
    slot_t *slot = find_slot(self, NULL);
    if (slot == NULL) {
        PyErr_Format(PyExc_RuntimeError,
                     "motor_process.subscribe: all %d subscriber slots are taken; unsubscribe a motor or "
                     "controller you no longer use",
                     OB_SCHEDULER_MAX_SUBSCRIBERS);
        return NULL;
    }
    slot->fn = fn;
    slot->ctx = ctx;
    slot->owner = self;
    if (!ob_scheduler_subscribe(&self->sched, dispatch, slot)) {
        slot->fn = NULL;
        slot->ctx = NULL;
        PyErr_SetString(PyExc_RuntimeError, "motor_process.subscribe: the scheduler registry is full");
        return NULL;
    }
    Py_INCREF(obj);
    slot->obj = obj;
    Py_RETURN_NONE;
}

static PyObject *mp_unsubscribe(MotorProcessObject *self, PyObject *obj) {
    slot_t *slot = find_slot(self, obj);
    if (slot != NULL) {
        release_slot(self, slot);
    }
    Py_RETURN_NONE;
}

static PyObject *mp_is_subscribed(MotorProcessObject *self, PyObject *obj) {
    return PyBool_FromLong(find_slot(self, obj) != NULL);
}

static PyTypeObject MotorProcessType;

/* tick() for C callers (the simulator's physics callback, through py_capi.h): no Python frame. */
int ob_py_motor_process_tick(PyObject *process, uint32_t now_ms) {
    if (!PyObject_TypeCheck(process, &MotorProcessType)) {
        PyErr_Format(PyExc_TypeError, "motor_process tick: expected a MotorProcess, not %.100s",
                     Py_TYPE(process)->tp_name);
        return -1;
    }
    MotorProcessObject *self = (MotorProcessObject *)process;
    /* A subscriber may tick this process re-entrantly from Python; keep the
     * outer tick's error slot intact by saving it around this round. */
    PyObject *outer_type = self->error_type, *outer_value = self->error_value, *outer_tb = self->error_tb;
    self->error_type = self->error_value = self->error_tb = NULL;
    ob_scheduler_tick(&self->sched, now_ms);
    PyObject *type = self->error_type, *value = self->error_value, *tb = self->error_tb;
    self->error_type = outer_type;
    self->error_value = outer_value;
    self->error_tb = outer_tb;
    if (type != NULL) {
        PyErr_Restore(type, value, tb);
        return -1;
    }
    return 0;
}

static PyObject *mp_tick(MotorProcessObject *self, PyObject *arg) {
    uint32_t now_ms;
    if (ob_py_time_ms(arg, "motor_process.tick", &now_ms) < 0) {
        return NULL;
    }
    if (ob_py_motor_process_tick((PyObject *)self, now_ms) < 0) {
        return NULL;
    }
    Py_RETURN_NONE;
}

static PyObject *mp_is_running(MotorProcessObject *self, PyObject *unused) {
    (void)unused;
    return PyBool_FromLong(self->sched.count > 0);
}

static PyObject *mp_now_ms(MotorProcessObject *self, PyObject *unused) {
    (void)unused;
    return PyLong_FromUnsignedLong(self->sched.now_ms);
}

static PyObject *mp_reset(MotorProcessObject *self, PyObject *unused) {
    (void)unused;
    for (int i = 0; i < OB_SCHEDULER_MAX_SUBSCRIBERS; i++) {
        if (self->slots[i].obj != NULL) {
            release_slot(self, &self->slots[i]);
        }
    }
    ob_scheduler_init(&self->sched);
    Py_RETURN_NONE;
}

static PyObject *mp_subscribers(MotorProcessObject *self, PyObject *unused) {
    (void)unused;
    PyObject *list = PyList_New(0);
    if (list == NULL) {
        return NULL;
    }
    /* In tick order, which is the core registry's order. */
    for (int i = 0; i < self->sched.count; i++) {
        slot_t *slot = (slot_t *)self->sched.subscribers[i].ctx;
        if (PyList_Append(list, slot->obj) < 0) {
            Py_DECREF(list);
            return NULL;
        }
    }
    return list;
}

static PyObject *mp_get_u32(MotorProcessObject *self, void *closure) {
    const uint32_t *field = (const uint32_t *)((const char *)&self->sched + (size_t)closure);
    return PyLong_FromUnsignedLong(*field);
}

static PyObject *mp_get_count(MotorProcessObject *self, void *closure) {
    (void)closure;
    return PyLong_FromLong(self->sched.count);
}

static int mp_traverse(MotorProcessObject *self, visitproc visit, void *arg) {
    for (int i = 0; i < OB_SCHEDULER_MAX_SUBSCRIBERS; i++) {
        Py_VISIT(self->slots[i].obj);
    }
    Py_VISIT(self->error_type);
    Py_VISIT(self->error_value);
    Py_VISIT(self->error_tb);
    return 0;
}

static int mp_clear(MotorProcessObject *self) {
    for (int i = 0; i < OB_SCHEDULER_MAX_SUBSCRIBERS; i++) {
        if (self->slots[i].obj != NULL) {
            release_slot(self, &self->slots[i]);
        }
    }
    Py_CLEAR(self->error_type);
    Py_CLEAR(self->error_value);
    Py_CLEAR(self->error_tb);
    return 0;
}

static void mp_dealloc(MotorProcessObject *self) {
    PyObject_GC_UnTrack(self);
    mp_clear(self);
    Py_TYPE(self)->tp_free((PyObject *)self);
}

static PyObject *mp_new(PyTypeObject *type, PyObject *args, PyObject *kwargs) {
    (void)args;
    (void)kwargs;
    MotorProcessObject *self = (MotorProcessObject *)type->tp_alloc(type, 0);
    if (self != NULL) {
        ob_scheduler_init(&self->sched);
        for (int i = 0; i < OB_SCHEDULER_MAX_SUBSCRIBERS; i++) {
            self->slots[i].owner = self;
        }
    }
    return (PyObject *)self;
}

static PyMethodDef mp_methods[] = {
    {"subscribe", (PyCFunction)mp_subscribe, METH_O,
     "subscribe(obj): tick obj every tick: a Servo or DriveBase natively, any other callable as "
     "callable(now_ms). Subscribing twice is a no-op."},
    {"unsubscribe", (PyCFunction)mp_unsubscribe, METH_O, "unsubscribe(obj): stop ticking obj (no-op if absent)."},
    {"is_subscribed", (PyCFunction)mp_is_subscribed, METH_O, "is_subscribed(obj) -> bool"},
    {"tick", (PyCFunction)mp_tick, METH_O,
     "tick(now_ms): advance the clock to now_ms (measured, wrapping at 2**32) and tick every subscriber once. "
     "Raises the first error a subscriber raised, after all of them ran."},
    {"is_running", (PyCFunction)mp_is_running, METH_NOARGS, "True while anything is subscribed."},
    {"now_ms", (PyCFunction)mp_now_ms, METH_NOARGS, "The clock as of the last tick."},
    {"reset", (PyCFunction)mp_reset, METH_NOARGS,
     "Unsubscribe everything and forget the clock (the runtime does this between programs)."},
    {"subscribers", (PyCFunction)mp_subscribers, METH_NOARGS, "The subscribers, in tick order."},
    {"hard_tick_count", (PyCFunction)ob_py_hard_tick_count, METH_NOARGS,
     "Hard ticks (the 1 kHz timer below the interpreter) delivered since it started."},
    {"hard_tick_selftest", (PyCFunction)(void (*)(void))ob_py_hard_tick_selftest, METH_VARARGS | METH_KEYWORDS,
     "hard_tick_selftest(duration_ms=100) -> (ticks, expected): run the hard tick for a while and check its "
     "rate; RuntimeError naming the counts when it is off by more than 10 %."},
    {NULL, NULL, 0, NULL},
};

static PyGetSetDef mp_getset[] = {
    {"tick_count", (getter)mp_get_u32, NULL, "Ticks dispatched since the last reset.",
     (void *)offsetof(ob_scheduler_t, tick_count)},
    {"late_ticks", (getter)mp_get_u32, NULL, "Ticks that came more than 1 ms after the previous one.",
     (void *)offsetof(ob_scheduler_t, late_ticks)},
    {"last_dt_ms", (getter)mp_get_u32, NULL, "Measured spacing of the last two ticks.",
     (void *)offsetof(ob_scheduler_t, last_dt_ms)},
    {"count", (getter)mp_get_count, NULL, "Number of subscribers.", NULL},
    {NULL, NULL, NULL, NULL, NULL},
};

static PyTypeObject MotorProcessType = {
    PyVarObject_HEAD_INIT(NULL, 0)
    .tp_name = "openbricks_native.MotorProcess",
    .tp_basicsize = sizeof(MotorProcessObject),
    .tp_flags = Py_TPFLAGS_DEFAULT | Py_TPFLAGS_HAVE_GC,
    .tp_doc = "MotorProcess()\n\n"
              "The control tick's subscriber registry and dispatch. The module's motor_process is the one the "
              "hub runtime uses; tests and simulations may build their own.",
    .tp_new = mp_new,
    .tp_init = (initproc)mp_init,
    .tp_dealloc = (destructor)mp_dealloc,
    .tp_traverse = (traverseproc)mp_traverse,
    .tp_clear = (inquiry)mp_clear,
    .tp_methods = mp_methods,
    .tp_getset = mp_getset,
};

static int add_type(PyObject *module, const char *name, PyTypeObject *type) {
    if (PyType_Ready(type) < 0) {
        return -1;
    }
    Py_INCREF(type);
    if (PyModule_AddObject(module, name, (PyObject *)type) < 0) {
        Py_DECREF(type);
        return -1;
    }
    return 0;
}

int ob_py_add_scheduler(PyObject *module) {
    if (add_type(module, "Subscriber", &ob_py_subscriber_type) < 0 ||
        add_type(module, "MotorProcess", &MotorProcessType) < 0) {
        return -1;
    }
    PyObject *process = PyObject_CallNoArgs((PyObject *)&MotorProcessType);
    if (process == NULL) {
        return -1;
    }
    if (PyModule_AddObject(module, "motor_process", process) < 0) {
        Py_DECREF(process);
        return -1;
    }
    return 0;
}
