/*
 * ServoWire: the simulated robot's serial bus as the firmware's bus engine sees it, in C.
 *
 * An ob_uart_t (uart.h) with the byte timing of a 1 Mbaud half-duplex line:
 * a request occupies the line for its bytes (10 bit times each), the
 * addressed servo answers after its return delay, and its reply occupies the
 * line in turn. The wire keeps its own microsecond clock, never behind the
 * physics clock (one MuJoCo step per millisecond), so the engine's reads,
 * deadlines and bus budget run on simulated time exactly as on a hub; a
 * reply that would land after the reader's deadline is lost, as on a bus.
 *
 * Behind the wire are the servos a DriveBase adopted: the shared servo
 * firmware emulation (emulated_servo.c: register file, PING, READ, WRITE,
 * SYNC WRITE), each servo's shaft a simulated wheel (its WheelIO in the
 * servo's shaft frame). In open-loop duty mode the goal time register is the
 * wheel's duty; in wheel mode (drive="wheel") the goal speed register feeds
 * the servo's own speed loop, modelled as feed-forward plus a proportional
 * term. A servo can be made silent (an unplugged cable). Servos not adopted
 * are answered by the Python register emulation (sim/serial_bus.py) instead,
 * through the shim's machine.UART; adoption moves a servo onto this wire.
 *
 * SerialBus(wire.uart()) runs the engine over it with no Python call per tick.
 */
#include <math.h>
#include <string.h>

#include "emulated_servo.h"
#include "mjcontrol.h"
#include "scs.h"
#include "uart.h"

#define COUNTS_PER_REV ((double)OB_SCS_COUNTS_PER_REV)
/* Wheel mode (drive="wheel"): the servo's own speed loop, feed-forward over its no-load speed
 * plus a proportional term, updated with every packet the engine sends (each tick). */
#define WHEEL_NO_LOAD_DPS 888.0
#define WHEEL_KP_PCT_PER_DPS 0.3
/* An ST-3032 starts its reply this long after the request's last byte (firmware latency). */
#define DEFAULT_RETURN_DELAY_US 20u

typedef struct {
    PyObject_HEAD
    ControllerObject *controller;
    ob_uart_t uart;
    uint32_t byte_us;
    uint32_t return_delay_us;
    uint64_t clock_us;
    uint64_t line_free_us;
    ob_emu_bus_t bus;
    WheelIOObject *wheels[OB_EMU_MAX_SERVOS]; /* strong references, by servo index; servo shaft frame */
    uint64_t reply_done_us; /* when the last reply byte is in */
    uint64_t line_busy_us;  /* line time used so far, requests and replies */
} ServoWireObject;

static uint64_t wire_now(ServoWireObject *self) {
    uint64_t physics_us = self->controller->now_ms * 1000u;
    if (self->clock_us < physics_us) {
        self->clock_us = physics_us;
    }
    return self->clock_us;
}

/* ---- Each servo's shaft: a simulated wheel ---- */

/* Drive the wheel as the mode, torque and goal registers ask. */
static void apply(ServoWireObject *self, int index) {
    const uint8_t *regs = self->bus.servos[index].regs;
    const WheelIOObject *wheel = self->wheels[index];
    const ob_motor_io_t *io = &wheel->base.io;
    if (regs[OB_SCS_REG_TORQUE_ENABLE] == 0u) {
        io->write_coast(io->ctx);
        return;
    }
    float duty = 0.0f;
    if (regs[OB_SCS_REG_MODE] == OB_SCS_MODE_DUTY) {
        duty = (float)ob_scs_sm_decode(ob_scs_get_u16(&regs[OB_SCS_REG_GOAL_TIME]), OB_SCS_DUTY_SIGN_BIT) / 10.0f;
    } else if (regs[OB_SCS_REG_MODE] == OB_SCS_MODE_WHEEL) {
        uint16_t raw = ob_scs_get_u16(&regs[OB_SCS_REG_GOAL_SPEED]);
        double goal_dps = ob_scs_sm_decode(raw, OB_SCS_SPEED_SIGN_BIT) * (360.0 / COUNTS_PER_REV);
        double speed_dps = wheel->sign * *wheel->wheel->qvel * RAD_TO_DEG;
        double pct = 100.0 * goal_dps / WHEEL_NO_LOAD_DPS + WHEEL_KP_PCT_PER_DPS * (goal_dps - speed_dps);
        duty = (float)(pct > 100.0 ? 100.0 : pct < -100.0 ? -100.0 : pct);
    }
    io->write_duty(io->ctx, duty);
}

static void shaft_written(void *ctx, int index, uint8_t address, size_t n) {
    if (ob_emu_touched(address, n, OB_SCS_REG_MODE) || ob_emu_touched(address, n, OB_SCS_REG_TORQUE_ENABLE) ||
        ob_emu_touched(address, n, OB_SCS_REG_GOAL_TIME) || ob_emu_touched(address, n, OB_SCS_REG_GOAL_TIME + 1u) ||
        ob_emu_touched(address, n, OB_SCS_REG_GOAL_SPEED) || ob_emu_touched(address, n, OB_SCS_REG_GOAL_SPEED + 1u)) {
        apply(ctx, index);
    }
}

static void shaft_sense(void *ctx, int index, double *counts, double *speed_cps, double *load_permille) {
    const WheelIOObject *io = ((ServoWireObject *)ctx)->wheels[index];
    *counts = io->sign * *io->wheel->qpos * (COUNTS_PER_REV / (2.0 * 3.14159265358979323846));
    *speed_cps = io->sign * *io->wheel->qvel * RAD_TO_DEG * (COUNTS_PER_REV / 360.0);
    *load_permille = io->wheel->coasting ? 0.0 : io->sign * io->wheel->duty * 1000.0;
}

/* ---- The wire (ob_uart_t) ---- */

static bool wire_write(void *ctx, const uint8_t *data, size_t n) {
    ServoWireObject *self = ctx;
    uint64_t now = wire_now(self);
    uint64_t start = now > self->line_free_us ? now : self->line_free_us;
    uint64_t sent = start + (uint64_t)n * self->byte_us;
    self->line_busy_us += (uint64_t)n * self->byte_us;
    self->clock_us = sent; /* half duplex: the write returns once the bytes are out */
    self->line_free_us = sent;
    self->bus.reply_len = 0;
    ob_emu_bus_write(&self->bus, data, n, (uint32_t)sent);
    if (self->bus.reply_len > 0) {
        self->reply_done_us = sent + self->return_delay_us + (uint64_t)self->bus.reply_len * self->byte_us;
        self->line_free_us = self->reply_done_us;
        self->line_busy_us += (uint64_t)self->bus.reply_len * self->byte_us;
    }
    return true;
}

static size_t wire_read(void *ctx, uint8_t *buf, size_t cap, uint32_t timeout_us) {
    ServoWireObject *self = ctx;
    uint64_t now = wire_now(self);
    if (self->bus.reply_len == 0 || self->reply_done_us > now + timeout_us) {
        self->clock_us = now + timeout_us; /* waited the whole timeout */
        return 0;
    }
    if (self->reply_done_us > now) {
        self->clock_us = self->reply_done_us;
    }
    return ob_emu_bus_read(&self->bus, buf, cap);
}

static void wire_flush_input(void *ctx) {
    ((ServoWireObject *)ctx)->bus.reply_len = 0;
}

static uint32_t wire_now_us(void *ctx) {
    return (uint32_t)wire_now(ctx);
}

/* ---- Python type ---- */

static int sw_init(ServoWireObject *self, PyObject *args, PyObject *kwargs) {
    static char *kwlist[] = {"controller", "baud", "return_delay_us", NULL};
    PyObject *controller;
    unsigned long baud = 1000000ul, delay = DEFAULT_RETURN_DELAY_US;
    if (!PyArg_ParseTupleAndKeywords(args, kwargs, "O|kk:ServoWire", kwlist, &controller, &baud, &delay)) {
        return -1;
    }
    if (self->controller != NULL) {
        PyErr_SetString(PyExc_RuntimeError, "ServoWire is already initialised");
        return -1;
    }
    if (baud < 9600ul || baud > 4000000ul || delay > 100000ul) {
        PyErr_SetString(PyExc_ValueError, "ServoWire: baud must be 9600..4000000 and return_delay_us <= 100000");
        return -1;
    }
    if (!PyObject_HasAttrString(controller, "add_wheel")) {
        PyErr_SetString(PyExc_TypeError, "ServoWire: controller must be the simulation's Controller");
        return -1;
    }
    self->controller = (ControllerObject *)Py_NewRef(controller);
    self->byte_us = ob_uart_byte_us((uint32_t)baud);
    self->return_delay_us = (uint32_t)delay;
    self->uart = (ob_uart_t){wire_write, wire_read, wire_flush_input, wire_now_us, self};
    ob_emu_bus_init(&self->bus, (ob_emu_shaft_t){NULL, shaft_sense, shaft_written, self});
    return 0;
}

static int sw_traverse(ServoWireObject *self, visitproc visit, void *arg) {
    Py_VISIT(self->controller);
    for (int i = 0; i < OB_EMU_MAX_SERVOS; i++) {
        Py_VISIT(self->wheels[i]);
    }
    return 0;
}

static int sw_clear(ServoWireObject *self) {
    for (int i = 0; i < OB_EMU_MAX_SERVOS; i++) {
        ob_emu_bus_remove(&self->bus, i);
        Py_CLEAR(self->wheels[i]);
    }
    Py_CLEAR(self->controller);
    return 0;
}

static void sw_dealloc(ServoWireObject *self) {
    PyObject_GC_UnTrack(self);
    sw_clear(self);
    Py_TYPE(self)->tp_free((PyObject *)self);
}

static int id_arg(PyObject *obj, uint8_t *id) {
    long value = PyLong_AsLong(obj);
    if (value == -1 && PyErr_Occurred()) {
        return -1;
    }
    if (value < 0 || value > (long)OB_SCS_MAX_SERVO_ID) {
        PyErr_Format(PyExc_ValueError, "ServoWire: servo id %ld is outside 0..253", value);
        return -1;
    }
    *id = (uint8_t)value;
    return 0;
}

static PyObject *sw_attach(ServoWireObject *self, PyObject *args) {
    PyObject *id_obj, *wheel;
    uint8_t id;
    if (!PyArg_ParseTuple(args, "OO!:attach", &id_obj, &WheelIOType, &wheel) || id_arg(id_obj, &id) < 0) {
        return NULL;
    }
    if (self->controller == NULL || ob_emu_bus_find(&self->bus, id) >= 0) {
        PyErr_Format(PyExc_ValueError, "ServoWire.attach: servo id %d is already on the wire", id);
        return NULL;
    }
    int index = ob_emu_bus_add(&self->bus, id);
    if (index < 0) {
        PyErr_Format(PyExc_ValueError, "ServoWire.attach: at most %d servos", OB_EMU_MAX_SERVOS);
        return NULL;
    }
    Py_XSETREF(self->wheels[index], (WheelIOObject *)Py_NewRef(wheel));
    Py_RETURN_NONE;
}

static PyObject *sw_detach(ServoWireObject *self, PyObject *arg) {
    uint8_t id;
    if (id_arg(arg, &id) < 0) {
        return NULL;
    }
    int index = ob_emu_bus_find(&self->bus, id);
    if (index >= 0) {
        ob_emu_bus_remove(&self->bus, index);
        Py_CLEAR(self->wheels[index]);
    }
    Py_RETURN_NONE;
}

static PyObject *sw_set_silent(ServoWireObject *self, PyObject *args) {
    PyObject *id_obj;
    int silent;
    uint8_t id;
    if (!PyArg_ParseTuple(args, "Op:set_silent", &id_obj, &silent) || id_arg(id_obj, &id) < 0) {
        return NULL;
    }
    int index = ob_emu_bus_find(&self->bus, id);
    if (index < 0) {
        PyErr_Format(PyExc_ValueError, "ServoWire.set_silent: servo id %d is not on the wire", id);
        return NULL;
    }
    self->bus.servos[index].silent = silent != 0;
    Py_RETURN_NONE;
}

static void release_capsule(PyObject *capsule) {
    Py_XDECREF((PyObject *)PyCapsule_GetContext(capsule));
}

static PyObject *sw_uart(ServoWireObject *self, PyObject *unused) {
    (void)unused;
    if (self->controller == NULL) {
        PyErr_SetString(PyExc_RuntimeError, "ServoWire was never initialised");
        return NULL;
    }
    PyObject *capsule = PyCapsule_New(&self->uart, OB_UART_CAPSULE, release_capsule);
    if (capsule == NULL || PyCapsule_SetContext(capsule, Py_NewRef(self)) < 0) {
        Py_XDECREF(capsule);
        return NULL;
    }
    return capsule;
}

static PyObject *sw_get_stats(ServoWireObject *self, void *closure) {
    (void)closure;
    return Py_BuildValue("{s:K,s:k,s:K}", "line_busy_us", (unsigned long long)self->line_busy_us, "packets",
                         (unsigned long)self->bus.packets, "clock_us", (unsigned long long)self->clock_us);
}

static PyMethodDef sw_methods[] = {
    {"attach", (PyCFunction)sw_attach, METH_VARARGS,
     "attach(servo_id, wheel_io): the servo answers on this wire, driving wheel_io (its shaft frame)."},
    {"detach", (PyCFunction)sw_detach, METH_O, "detach(servo_id): the servo leaves the wire."},
    {"set_silent", (PyCFunction)sw_set_silent, METH_VARARGS, "set_silent(servo_id, silent): unplug / replug."},
    {"uart", (PyCFunction)sw_uart, METH_NOARGS, "The wire as a capsule for openbricks_native.SerialBus(uart)."},
    {NULL, NULL, 0, NULL},
};

static PyGetSetDef sw_getset[] = {
    {"stats", (getter)sw_get_stats, NULL, "line_busy_us, packets and the wire's clock_us.", NULL},
    {NULL, NULL, NULL, NULL, NULL},
};

static PyTypeObject ServoWireType = {
    PyVarObject_HEAD_INIT(NULL, 0)
    .tp_name = "openbricks_mjcontrol.ServoWire",
    .tp_basicsize = sizeof(ServoWireObject),
    .tp_flags = Py_TPFLAGS_DEFAULT | Py_TPFLAGS_HAVE_GC,
    .tp_doc = "ServoWire(controller, baud=1000000, return_delay_us=20): the emulated serial bus of the adopted "
              "servos, with 1 Mbaud half-duplex byte timing on simulated time.",
    .tp_new = PyType_GenericNew,
    .tp_init = (initproc)sw_init,
    .tp_dealloc = (destructor)sw_dealloc,
    .tp_traverse = (traverseproc)sw_traverse,
    .tp_clear = (inquiry)sw_clear,
    .tp_methods = sw_methods,
    .tp_getset = sw_getset,
};

int ob_sim_add_servo_wire(PyObject *module) {
    if (PyType_Ready(&ServoWireType) < 0) {
        return -1;
    }
    return PyModule_AddObjectRef(module, "ServoWire", (PyObject *)&ServoWireType);
}
