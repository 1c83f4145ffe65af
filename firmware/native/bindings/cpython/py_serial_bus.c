/*
 * SerialBus: the serial-bus engine (serial_bus.c) for the host (MicroPython: mp_serial_bus.c).
 *
 * SerialBus(uart, baud=1000000) runs the engine over either
 *   - a native wire: a capsule named OB_UART_CAPSULE holding an ob_uart_t
 *     (the simulator's emulated bus, with real byte timing), so a tick runs
 *     with no Python call; or
 *   - a Python UART: an object with write(bytes), read(n) -> bytes or None and
 *     any() (machine.UART, or the tests' fake bus with scripted servos). Its
 *     replies are there as soon as the request is written, so the adapter
 *     keeps the wire's clock itself: each byte costs its time at baud, and a
 *     read that finds nothing costs the whole wait.
 *
 * serial_bus(uart_id, tx=None, rx=None, baud=1000000) is the runtime's way in:
 * on the host it opens machine.UART(uart_id, ...) (the fake board's, in the
 * tests) and returns a SerialBus over it. The engine subscribes itself to
 * motor_process when it adopts its first servo and unsubscribes when the last
 * one is released. Errors from a Python UART during a tick are kept and
 * raised by motor_process after the round, as with the other subscribers.
 */
#include <string.h>

#include "bindings.h"
#include "py_args.h"
#include "py_capi.h"
#include "py_motor_io.h"
#include "py_subscriber.h"
#include "serial_bus.h"

typedef struct {
    ob_py_subscriber_t base;
    ob_serial_bus_t bus;
    PyObject *uart; /* the Python UART or the capsule (kept alive) */
    uint32_t clock_us; /* a Python UART's wire clock */
    uint32_t byte_us;
    PyObject *error_type, *error_value, *error_tb;
} SerialBusObject;

typedef struct {
    ob_py_motor_io_t base;
    SerialBusObject *owner;
    int slot;
} SlotIOObject;

static PyTypeObject SerialBusType;
static PyTypeObject SlotIOType;

/* ---- A Python UART as an ob_uart_t ---- */

static void stash(SerialBusObject *self) {
    if (self->error_type == NULL) {
        PyErr_Fetch(&self->error_type, &self->error_value, &self->error_tb);
    } else {
        PyErr_WriteUnraisable((PyObject *)self);
    }
}

static int raise_stashed(SerialBusObject *self) {
    if (self->error_type == NULL) {
        return 0;
    }
    PyErr_Restore(self->error_type, self->error_value, self->error_tb);
    self->error_type = self->error_value = self->error_tb = NULL;
    return -1;
}

static bool py_write(void *ctx, const uint8_t *data, size_t n) {
    SerialBusObject *self = ctx;
    if (self->error_type != NULL) {
        return false; /* no Python call while an error waits to be raised */
    }
    self->clock_us += (uint32_t)n * self->byte_us;
    PyObject *result = PyObject_CallMethod(self->uart, "write", "y#", (const char *)data, (Py_ssize_t)n);
    if (result == NULL) {
        stash(self);
        return false;
    }
    Py_DECREF(result);
    return true;
}

static size_t py_read(void *ctx, uint8_t *buf, size_t cap, uint32_t timeout_us) {
    SerialBusObject *self = ctx;
    if (self->error_type != NULL) {
        self->clock_us += timeout_us;
        return 0;
    }
    PyObject *data = PyObject_CallMethod(self->uart, "read", "n", (Py_ssize_t)cap);
    if (data == NULL) {
        stash(self);
        self->clock_us += timeout_us;
        return 0;
    }
    size_t n = 0;
    if (data != Py_None) {
        Py_buffer view;
        if (PyObject_GetBuffer(data, &view, PyBUF_SIMPLE) < 0) {
            stash(self);
        } else {
            n = (size_t)view.len < cap ? (size_t)view.len : cap;
            memcpy(buf, view.buf, n);
            PyBuffer_Release(&view);
        }
    }
    Py_DECREF(data);
    self->clock_us += n > 0 ? (uint32_t)n * self->byte_us : timeout_us;
    return n;
}

static void py_flush_input(void *ctx) {
    SerialBusObject *self = ctx;
    if (self->error_type != NULL) {
        return;
    }
    PyObject *waiting = PyObject_CallMethod(self->uart, "any", NULL);
    if (waiting == NULL) {
        stash(self);
        return;
    }
    int some = PyObject_IsTrue(waiting);
    Py_DECREF(waiting);
    if (some > 0) {
        PyObject *dropped = PyObject_CallMethod(self->uart, "read", NULL);
        if (dropped == NULL) {
            stash(self);
            return;
        }
        Py_DECREF(dropped);
    }
}

static uint32_t py_now_us(void *ctx) {
    return ((SerialBusObject *)ctx)->clock_us;
}

/* ---- The engine ---- */

static void serial_bus_tick_fn(void *ctx, uint32_t now_ms) {
    SerialBusObject *self = ctx;
    ob_serial_bus_tick(&self->bus, now_ms);
    (void)raise_stashed(self); /* motor_process raises it after the round */
}

static int sb_init(SerialBusObject *self, PyObject *args, PyObject *kwargs) {
    static char *kwlist[] = {"uart", "baud", NULL};
    PyObject *uart;
    unsigned long baud = OB_SERIAL_BUS_DEFAULT_BAUD;
    if (!PyArg_ParseTupleAndKeywords(args, kwargs, "O|k:SerialBus", kwlist, &uart, &baud)) {
        return -1;
    }
    if (self->uart != NULL) {
        PyErr_SetString(PyExc_RuntimeError, "SerialBus is already initialised");
        return -1;
    }
    if (baud < 9600 || baud > 4000000) {
        PyErr_Format(PyExc_ValueError, "SerialBus(): baud=%lu is outside 9600..4000000", baud);
        return -1;
    }
    ob_uart_t wire;
    if (PyCapsule_CheckExact(uart)) {
        const ob_uart_t *native = PyCapsule_GetPointer(uart, OB_UART_CAPSULE);
        if (native == NULL) {
            return -1;
        }
        wire = *native;
    } else {
        static const char *const needed[] = {"write", "read", "any"};
        for (size_t i = 0; i < 3; i++) {
            if (!PyObject_HasAttrString(uart, needed[i])) {
                PyErr_Format(PyExc_TypeError,
                             "SerialBus(): uart must be a UART (write, read, any) or a native wire capsule, "
                             "not %.100s (it has no %s())",
                             Py_TYPE(uart)->tp_name, needed[i]);
                return -1;
            }
        }
        wire = (ob_uart_t){py_write, py_read, py_flush_input, py_now_us, self};
    }
    self->uart = Py_NewRef(uart);
    self->byte_us = ob_uart_byte_us((uint32_t)baud);
    ob_serial_bus_init(&self->bus, &wire, (uint32_t)baud);
    self->base.tick_fn = serial_bus_tick_fn;
    self->base.tick_ctx = self;
    return 0;
}

static int sb_traverse(SerialBusObject *self, visitproc visit, void *arg) {
    Py_VISIT(self->uart);
    return 0;
}

static int sb_clear(SerialBusObject *self) {
    Py_CLEAR(self->uart);
    Py_CLEAR(self->error_type);
    Py_CLEAR(self->error_value);
    Py_CLEAR(self->error_tb);
    return 0;
}

static void sb_dealloc(SerialBusObject *self) {
    PyObject_GC_UnTrack(self);
    sb_clear(self);
    Py_TYPE(self)->tp_free((PyObject *)self);
}

static int ready(SerialBusObject *self) {
    if (self->uart == NULL) {
        PyErr_SetString(PyExc_RuntimeError, "SerialBus was never initialised");
        return -1;
    }
    return 0;
}

/* The adopted slot named by obj, or NULL with ValueError set. */
static ob_serial_bus_slot_t *slot_arg(SerialBusObject *self, PyObject *obj, int *index) {
    if (ready(self) < 0) {
        return NULL;
    }
    long slot = PyLong_Check(obj) && !PyBool_Check(obj) ? PyLong_AsLong(obj) : -1;
    if (slot == -1 && PyErr_Occurred()) {
        PyErr_Clear();
    }
    ob_serial_bus_slot_t *found = slot >= 0 && slot < OB_SERIAL_BUS_MAX_SLOTS
                                      ? ob_serial_bus_slot(&self->bus, (int)slot)
                                      : NULL;
    if (found == NULL) {
        PyObject *repr = PyObject_Repr(obj);
        PyErr_Format(PyExc_ValueError, "slot %s is not an adopted servo on this bus engine",
                     repr != NULL ? PyUnicode_AsUTF8(repr) : "?");
        Py_XDECREF(repr);
        return NULL;
    }
    if (index != NULL) {
        *index = (int)slot;
    }
    return found;
}

static int set_subscribed(SerialBusObject *self, int on) {
    PyObject *module = PyImport_ImportModule("openbricks_native");
    if (module == NULL) {
        return -1;
    }
    PyObject *process = PyObject_GetAttrString(module, "motor_process");
    Py_DECREF(module);
    if (process == NULL) {
        return -1;
    }
    PyObject *result = PyObject_CallMethod(process, on ? "subscribe" : "unsubscribe", "O", (PyObject *)self);
    Py_DECREF(process);
    if (result == NULL) {
        return -1;
    }
    Py_DECREF(result);
    return 0;
}

static PyObject *sb_adopt(SerialBusObject *self, PyObject *args, PyObject *kwargs) {
    static char *kwlist[] = {"servo_id", "invert", "counts_per_rev", NULL};
    int servo_id, invert = 0, counts = OB_SERIAL_BUS_COUNTS_PER_REV;
    if (!PyArg_ParseTupleAndKeywords(args, kwargs, "i|pi:adopt", kwlist, &servo_id, &invert, &counts) ||
        ready(self) < 0) {
        return NULL;
    }
    if (counts != OB_SERIAL_BUS_COUNTS_PER_REV) {
        PyErr_Format(PyExc_ValueError, "adopt(counts_per_rev=%d): %s", counts,
                     ob_serial_bus_strerror(OB_SERIAL_BUS_E_COUNTS));
        return NULL;
    }
    int slot = -1;
    ob_serial_bus_error_t error = ob_serial_bus_adopt(&self->bus, servo_id, invert != 0, &slot);
    if (raise_stashed(self) < 0) {
        return NULL;
    }
    switch (error) {
        case OB_SERIAL_BUS_OK:
            break;
        case OB_SERIAL_BUS_E_SILENT:
            PyErr_Format(PyExc_OSError,
                         "motor is not responding on the bus: servo id %d did not answer when the bus engine "
                         "adopted it. Check the servo's power and TX/RX wiring, and that it really has that bus "
                         "id - `openbricks servo-id --scan` lists the ids actually answering on the bus.",
                         servo_id);
            return NULL;
        case OB_SERIAL_BUS_E_ADOPTED:
            PyErr_Format(PyExc_ValueError, "adopt(%d): servo id %d is already adopted (slot %d); release() it first",
                         servo_id, servo_id, slot);
            return NULL;
        default:
            PyErr_Format(PyExc_ValueError, "adopt(%d): %s", servo_id, ob_serial_bus_strerror(error));
            return NULL;
    }
    if (set_subscribed(self, 1) < 0) { /* idempotent; motor_process may have been reset since */
        return NULL;
    }
    return PyLong_FromLong(slot);
}

static PyObject *sb_release(SerialBusObject *self, PyObject *arg) {
    int index;
    if (slot_arg(self, arg, &index) == NULL) {
        return NULL;
    }
    (void)ob_serial_bus_release(&self->bus, index);
    if (raise_stashed(self) < 0) {
        return NULL;
    }
    if (!ob_serial_bus_active(&self->bus) && set_subscribed(self, 0) < 0) {
        return NULL;
    }
    Py_RETURN_NONE;
}

static PyObject *sb_motor_io(SerialBusObject *self, PyObject *arg) {
    int index;
    ob_serial_bus_slot_t *slot = slot_arg(self, arg, &index);
    if (slot == NULL) {
        return NULL;
    }
    SlotIOObject *io = PyObject_GC_New(SlotIOObject, &SlotIOType);
    if (io == NULL) {
        return NULL;
    }
    io->base.io = ob_serial_bus_motor_io(slot);
    io->owner = (SerialBusObject *)Py_NewRef(self);
    io->slot = index;
    PyObject_GC_Track(io);
    return (PyObject *)io;
}

static PyObject *sb_angle_deg(SerialBusObject *self, PyObject *arg) {
    ob_serial_bus_slot_t *slot = slot_arg(self, arg, NULL);
    if (slot == NULL) {
        return NULL;
    }
    if (!ob_serial_bus_answering(slot)) {
        Py_RETURN_NONE;
    }
    return PyFloat_FromDouble(ob_serial_bus_angle_deg(slot));
}

static PyObject *sb_speed_dps(SerialBusObject *self, PyObject *arg) {
    ob_serial_bus_slot_t *slot = slot_arg(self, arg, NULL);
    if (slot == NULL) {
        return NULL;
    }
    if (!ob_serial_bus_answering(slot)) {
        Py_RETURN_NONE;
    }
    return PyFloat_FromDouble(slot->speed_dps);
}

static PyObject *sb_load_pct(SerialBusObject *self, PyObject *arg) {
    ob_serial_bus_slot_t *slot = slot_arg(self, arg, NULL);
    if (slot == NULL) {
        return NULL;
    }
    if (!ob_serial_bus_answering(slot)) {
        Py_RETURN_NONE;
    }
    return PyFloat_FromDouble(slot->load_pct);
}

static PyObject *sb_stats(SerialBusObject *self, PyObject *arg) {
    ob_serial_bus_slot_t *slot = slot_arg(self, arg, NULL);
    if (slot == NULL) {
        return NULL;
    }
    return Py_BuildValue("(kkk)", (unsigned long)slot->replies, (unsigned long)slot->failed_reads,
                         (unsigned long)slot->failed_in_a_row);
}

static PyObject *sb_bus_stats(SerialBusObject *self, PyObject *unused) {
    (void)unused;
    if (ready(self) < 0) {
        return NULL;
    }
    return Py_BuildValue("{s:k,s:k,s:K,s:k}", "ticks", (unsigned long)self->bus.ticks, "last_tick_bus_us",
                         (unsigned long)self->bus.last_tick_bus_us, "bus_us_total",
                         (unsigned long long)self->bus.bus_us_total, "garbage_frames",
                         (unsigned long)self->bus.garbage_frames);
}

static PyObject *sb_tick(SerialBusObject *self, PyObject *arg) {
    uint32_t now_ms = (uint32_t)PyLong_AsUnsignedLongMask(arg);
    if (PyErr_Occurred() || ready(self) < 0) {
        return NULL;
    }
    ob_serial_bus_tick(&self->bus, now_ms);
    if (raise_stashed(self) < 0) {
        return NULL;
    }
    Py_RETURN_NONE;
}

/* ---- st_move_core: the slot's own moves and holds, and its flags ---- */

static PyObject *sb_move(SerialBusObject *self, PyObject *args, PyObject *kwargs) {
    static char *kwlist[] = {"slot", "speed_dps", "angle_deg", "then", "accel_dps2", NULL};
    static const char *where = "SerialBus.move";
    PyObject *slot_in, *speed_in, *angle_in, *then_in = NULL, *accel_in = Py_None;
    if (!PyArg_ParseTupleAndKeywords(args, kwargs, "OOO|OO:move", kwlist, &slot_in, &speed_in, &angle_in, &then_in,
                                     &accel_in)) {
        return NULL;
    }
    ob_serial_bus_slot_t *slot = slot_arg(self, slot_in, NULL);
    float speed, angle, accel = 0.0f;
    ob_then_t then = OB_THEN_HOLD;
    if (slot == NULL || ob_py_float(speed_in, where, "speed_dps", &speed) < 0 ||
        ob_py_float(angle_in, where, "angle_deg", &angle) < 0 ||
        (then_in != NULL && ob_py_then(then_in, where, &then) < 0) ||
        (accel_in != Py_None && ob_py_positive_float(accel_in, where, "accel_dps2", &accel) < 0)) {
        return NULL;
    }
    if (speed == 0.0f) {
        PyErr_Format(PyExc_ValueError, "%s: speed_dps must not be 0 (use hold() to stay in place)", where);
        return NULL;
    }
    ob_serial_bus_move(slot, speed, angle, then, accel);
    Py_RETURN_NONE;
}

static PyObject *sb_hold(SerialBusObject *self, PyObject *arg) {
    ob_serial_bus_slot_t *slot = slot_arg(self, arg, NULL);
    if (slot == NULL) {
        return NULL;
    }
    ob_serial_bus_hold(slot);
    Py_RETURN_NONE;
}

static PyObject *sb_end_move(SerialBusObject *self, PyObject *arg) {
    ob_serial_bus_slot_t *slot = slot_arg(self, arg, NULL);
    if (slot == NULL) {
        return NULL;
    }
    ob_serial_bus_end_move(slot);
    Py_RETURN_NONE;
}

static PyObject *sb_done(SerialBusObject *self, PyObject *arg) {
    ob_serial_bus_slot_t *slot = slot_arg(self, arg, NULL);
    if (slot == NULL) {
        return NULL;
    }
    if (ob_serial_bus_move_lost_feedback(slot)) {
        PyErr_Format(PyExc_OSError, "SerialBus.done(%d): servo id %d stopped answering mid-move; the move was halted",
                     (int)(slot - self->bus.slots), (int)slot->servo_id);
        return NULL;
    }
    return PyBool_FromLong(ob_serial_bus_arrived(slot));
}

static PyObject *sb_stalled(SerialBusObject *self, PyObject *args, PyObject *kwargs) {
    static char *kwlist[] = {"slot", "load_pct", "speed_dps", NULL};
    static const char *where = "SerialBus.stalled";
    PyObject *slot_in, *load_in = Py_None, *speed_in = Py_None;
    if (!PyArg_ParseTupleAndKeywords(args, kwargs, "O|OO:stalled", kwlist, &slot_in, &load_in, &speed_in)) {
        return NULL;
    }
    ob_serial_bus_slot_t *slot = slot_arg(self, slot_in, NULL);
    float load = OB_SERIAL_BUS_STALL_LOAD_PCT, speed = OB_SERIAL_BUS_STALL_SPEED_DPS;
    if (slot == NULL || (load_in != Py_None && ob_py_positive_float(load_in, where, "load_pct", &load) < 0) ||
        (speed_in != Py_None && ob_py_float(speed_in, where, "speed_dps", &speed) < 0)) {
        return NULL;
    }
    return PyBool_FromLong(ob_serial_bus_stalled(slot, load, speed));
}

static PyObject *sb_set_drive(SerialBusObject *self, PyObject *args, PyObject *kwargs) {
    static char *kwlist[] = {"slot", "drive", "max_dps", NULL};
    static const char *where = "SerialBus.set_drive";
    PyObject *slot_in, *max_in = Py_None;
    const char *drive;
    int index;
    if (!PyArg_ParseTupleAndKeywords(args, kwargs, "Os|O:set_drive", kwlist, &slot_in, &drive, &max_in) ||
        slot_arg(self, slot_in, &index) == NULL) {
        return NULL;
    }
    bool wheel = strcmp(drive, "wheel") == 0;
    if (!wheel && strcmp(drive, "duty") != 0) {
        PyErr_Format(PyExc_ValueError, "%s(drive='%s'): give \"duty\" (the engine closes the loop over raw duty) or "
                     "\"wheel\" (the servo's own speed controller)", where, drive);
        return NULL;
    }
    float max_dps = 0.0f;
    if (wheel && ob_py_positive_float(max_in, where, "max_dps", &max_dps) < 0) {
        return NULL;
    }
    ob_serial_bus_error_t error = ob_serial_bus_set_drive(&self->bus, index, wheel, max_dps);
    if (raise_stashed(self) < 0) {
        return NULL;
    }
    if (error != OB_SERIAL_BUS_OK) {
        PyErr_Format(PyExc_OSError, "%s: servo id %d is %s", where, (int)self->bus.slots[index].servo_id,
                     ob_serial_bus_strerror(error));
        return NULL;
    }
    Py_RETURN_NONE;
}

static PyMethodDef sb_methods[] = {
    {"set_drive", (PyCFunction)(void (*)(void))sb_set_drive, METH_VARARGS | METH_KEYWORDS,
     "set_drive(slot, drive, max_dps=None): 'duty' (open-loop duty) or 'wheel' (the servo's speed loop)."},
    {"move", (PyCFunction)(void (*)(void))sb_move, METH_VARARGS | METH_KEYWORDS,
     "move(slot, speed_dps, angle_deg, then='hold', accel_dps2=None): a position move by angle_deg on the tick."},
    {"hold", (PyCFunction)sb_hold, METH_O, "hold(slot): lock the shaft where it is, on the tick."},
    {"end_move", (PyCFunction)sb_end_move, METH_O, "end_move(slot): the slot's own move or hold stands down."},
    {"done", (PyCFunction)sb_done, METH_O, "done(slot): the arrival flag (True when no move is in flight)."},
    {"stalled", (PyCFunction)(void (*)(void))sb_stalled, METH_VARARGS | METH_KEYWORDS,
     "stalled(slot, load_pct=80, speed_dps=20): the stall flag (pushing hard, barely moving)."},
    {"adopt", (PyCFunction)(void (*)(void))sb_adopt, METH_VARARGS | METH_KEYWORDS,
     "adopt(servo_id, invert=False, counts_per_rev=4096) -> slot: take the servo onto the engine (duty mode, "
     "coasting)."},
    {"release", (PyCFunction)sb_release, METH_O, "release(slot): coast the servo and give it back (wheel mode)."},
    {"motor_io", (PyCFunction)sb_motor_io, METH_O, "motor_io(slot): the slot's native motor IO (user frame)."},
    {"angle_deg", (PyCFunction)sb_angle_deg, METH_O, "Multi-turn angle (user frame), or None while silent."},
    {"speed_dps", (PyCFunction)sb_speed_dps, METH_O, "Present speed (user frame), or None while silent."},
    {"load_pct", (PyCFunction)sb_load_pct, METH_O, "Present load, percent of stall (user frame), or None."},
    {"stats", (PyCFunction)sb_stats, METH_O, "stats(slot) -> (replies, failed_reads, failed_in_a_row)."},
    {"bus_stats", (PyCFunction)sb_bus_stats, METH_NOARGS,
     "The engine's counters: ticks, last_tick_bus_us, bus_us_total, garbage_frames."},
    {"tick", (PyCFunction)sb_tick, METH_O, "tick(now_ms): one tick's bus work (motor_process does this)."},
    {NULL, NULL, 0, NULL},
};

static PyTypeObject SerialBusType = {
    PyVarObject_HEAD_INIT(NULL, 0)
    .tp_name = "openbricks_native.SerialBus",
    .tp_basicsize = sizeof(SerialBusObject),
    .tp_flags = Py_TPFLAGS_DEFAULT | Py_TPFLAGS_HAVE_GC,
    .tp_new = PyType_GenericNew,
    .tp_init = (initproc)sb_init,
    .tp_dealloc = (destructor)sb_dealloc,
    .tp_traverse = (traverseproc)sb_traverse,
    .tp_clear = (inquiry)sb_clear,
    .tp_methods = sb_methods,
    .tp_doc = "SerialBus(uart, baud=1000000): the serial-bus engine over one UART of SCS servos; adopted "
              "servos are driven and read on the 1 kHz tick.",
};

/* ---- A slot's motor IO ---- */

static int sio_traverse(SlotIOObject *self, visitproc visit, void *arg) {
    Py_VISIT(self->owner);
    return 0;
}

static int sio_clear(SlotIOObject *self) {
    Py_CLEAR(self->owner);
    return 0;
}

static void sio_dealloc(SlotIOObject *self) {
    PyObject_GC_UnTrack(self);
    sio_clear(self);
    Py_TYPE(self)->tp_free((PyObject *)self);
}

static PyObject *sio_read_angle(SlotIOObject *self, PyObject *unused) {
    (void)unused;
    float angle;
    if (!self->base.io.read_angle(self->base.io.ctx, &angle)) {
        Py_RETURN_NONE;
    }
    return PyFloat_FromDouble(angle);
}

static PyObject *sio_write_duty(SlotIOObject *self, PyObject *arg) {
    float duty;
    if (ob_py_float(arg, "write_duty", "duty_pct", &duty) < 0) {
        return NULL;
    }
    self->base.io.write_duty(self->base.io.ctx, duty);
    Py_RETURN_NONE;
}

static PyObject *sio_coast(SlotIOObject *self, PyObject *unused) {
    (void)unused;
    self->base.io.write_coast(self->base.io.ctx);
    Py_RETURN_NONE;
}

static PyMethodDef sio_methods[] = {
    {"read_angle", (PyCFunction)sio_read_angle, METH_NOARGS, "The latest angle (user frame), or None."},
    {"write_duty", (PyCFunction)sio_write_duty, METH_O, "write_duty(duty_pct): the duty the next tick sends."},
    {"coast", (PyCFunction)sio_coast, METH_NOARGS, "Coast from the next tick on."},
    {NULL, NULL, 0, NULL},
};

static PyTypeObject SlotIOType = {
    PyVarObject_HEAD_INIT(NULL, 0)
    .tp_name = "openbricks_native.SerialBusSlotIO",
    .tp_basicsize = sizeof(SlotIOObject),
    .tp_flags = Py_TPFLAGS_DEFAULT | Py_TPFLAGS_HAVE_GC,
    .tp_dealloc = (destructor)sio_dealloc,
    .tp_traverse = (traverseproc)sio_traverse,
    .tp_clear = (inquiry)sio_clear,
    .tp_methods = sio_methods,
    .tp_doc = "One adopted servo's motor IO on a SerialBus engine.",
};

/* ---- serial_bus(uart_id, ...) ---- */

static PyObject *mod_serial_bus(PyObject *module, PyObject *args, PyObject *kwargs) {
    (void)module;
    static char *kwlist[] = {"uart_id", "tx", "rx", "baud", "dir_pin", NULL};
    int uart_id;
    PyObject *tx = Py_None, *rx = Py_None, *dir_pin = Py_None;
    unsigned long baud = OB_SERIAL_BUS_DEFAULT_BAUD;
    if (!PyArg_ParseTupleAndKeywords(args, kwargs, "i|OOkO:serial_bus", kwlist, &uart_id, &tx, &rx, &baud,
                                     &dir_pin)) {
        return NULL;
    }
    (void)dir_pin; /* the host's UARTs have no direction pin to drive */
    PyObject *machine = PyImport_ImportModule("machine");
    if (machine == NULL) {
        return NULL;
    }
    PyObject *uart_type = PyObject_GetAttrString(machine, "UART");
    Py_DECREF(machine);
    if (uart_type == NULL) {
        return NULL;
    }
    PyObject *uart_args = Py_BuildValue("(i)", uart_id);
    PyObject *uart_kwargs = Py_BuildValue("{s:k,s:O,s:O,s:i}", "baudrate", baud, "tx", tx, "rx", rx, "timeout", 0);
    PyObject *uart = NULL;
    if (uart_args != NULL && uart_kwargs != NULL) {
        uart = PyObject_Call(uart_type, uart_args, uart_kwargs);
    }
    Py_DECREF(uart_type);
    Py_XDECREF(uart_args);
    Py_XDECREF(uart_kwargs);
    if (uart == NULL) {
        return NULL;
    }
    PyObject *engine = PyObject_CallFunction((PyObject *)&SerialBusType, "Ok", uart, baud);
    Py_DECREF(uart);
    return engine;
}

static PyMethodDef module_functions[] = {
    {"serial_bus", (PyCFunction)(void (*)(void))mod_serial_bus, METH_VARARGS | METH_KEYWORDS,
     "serial_bus(uart_id, tx=None, rx=None, baud=1000000, dir_pin=None) -> SerialBus over machine.UART(uart_id)."},
    {NULL, NULL, 0, NULL},
};

int ob_py_add_serial_bus(PyObject *module) {
    SerialBusType.tp_base = &ob_py_subscriber_type;
    SlotIOType.tp_base = &ob_py_motor_io_type;
    if (PyType_Ready(&ob_py_motor_io_type) < 0 || PyType_Ready(&SerialBusType) < 0 ||
        PyType_Ready(&SlotIOType) < 0) {
        return -1;
    }
    if (PyModule_AddObjectRef(module, "SerialBus", (PyObject *)&SerialBusType) < 0) {
        return -1;
    }
    return PyModule_AddFunctions(module, module_functions);
}
