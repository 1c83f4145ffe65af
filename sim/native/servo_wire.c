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
 * Behind the wire are the servos a DriveBase adopted: each one an ST-3032's
 * firmware in open-loop duty mode over a simulated wheel (its WheelIO in the
 * servo's shaft frame). They answer PING, the 6-byte feedback READ (present
 * position as the multi-turn sign-magnitude window, speed, load), WRITE and
 * SYNC WRITE of torque enable, mode, the duty (goal time) and, for
 * drive="wheel", the goal speed register (wheel mode: the servo's own speed
 * loop, modelled as feed-forward plus a proportional term). A
 * servo can be made silent (an unplugged cable). Servos not adopted are
 * answered by the Python register emulation (sim/serial_bus.py) instead,
 * through the shim's machine.UART; adoption moves a servo onto this wire.
 *
 * SerialBus(wire.uart()) runs the engine over it with no Python call per tick.
 */
#include <math.h>
#include <string.h>

#include "mjcontrol.h"
#include "scs.h"
#include "uart.h"

#define MAX_SERVOS 8
#define COUNTS_PER_REV ((double)OB_SCS_COUNTS_PER_REV)
#define MULTI_TURN_SPAN ((int32_t)OB_SCS_MULTI_TURN_SPAN)
/* Wheel mode (drive="wheel"): the servo's own speed loop, feed-forward over its no-load speed
 * plus a proportional term, updated with every packet the engine sends (each tick). */
#define WHEEL_NO_LOAD_DPS 888.0
#define WHEEL_KP_PCT_PER_DPS 0.3
/* An ST-3032 starts its reply this long after the request's last byte (firmware latency). */
#define DEFAULT_RETURN_DELAY_US 20u

typedef struct {
    int used;
    uint8_t id;
    int silent;
    WheelIOObject *wheel; /* strong reference; servo shaft frame */
    uint8_t mode;
    int torque_on;
    uint16_t duty_raw; /* goal time register: 0.1 %, sign in bit 10 */
    uint16_t speed_raw; /* goal speed register: steps/s, sign in bit 15 */
} servo_t;

typedef struct {
    PyObject_HEAD
    ControllerObject *controller;
    ob_uart_t uart;
    uint32_t byte_us;
    uint32_t return_delay_us;
    uint64_t clock_us;
    uint64_t line_free_us;
    uint8_t reply[OB_SCS_MAX_FRAME];
    size_t reply_len;
    uint64_t reply_done_us; /* when the last reply byte is in */
    servo_t servos[MAX_SERVOS];
    uint64_t line_busy_us; /* line time used so far, requests and replies */
    unsigned long packets;
} ServoWireObject;

static servo_t *find(ServoWireObject *self, uint8_t id) {
    for (int i = 0; i < MAX_SERVOS; i++) {
        if (self->servos[i].used && self->servos[i].id == id) {
            return &self->servos[i];
        }
    }
    return NULL;
}

static uint64_t wire_now(ServoWireObject *self) {
    uint64_t physics_us = self->controller->now_ms * 1000u;
    if (self->clock_us < physics_us) {
        self->clock_us = physics_us;
    }
    return self->clock_us;
}

/* ---- One servo's firmware (duty mode) ---- */

static void apply(servo_t *servo) {
    const ob_motor_io_t *io = &servo->wheel->base.io;
    if (!servo->torque_on) {
        io->write_coast(io->ctx);
        return;
    }
    float duty = 0.0f;
    if (servo->mode == OB_SCS_MODE_DUTY) {
        duty = (float)ob_scs_sm_decode(servo->duty_raw, OB_SCS_DUTY_SIGN_BIT) / 10.0f;
    } else if (servo->mode == OB_SCS_MODE_WHEEL) {
        const WheelIOObject *wheel = servo->wheel;
        double goal_dps = ob_scs_sm_decode(servo->speed_raw, OB_SCS_SPEED_SIGN_BIT) * (360.0 / COUNTS_PER_REV);
        double speed_dps = wheel->sign * *wheel->wheel->qvel * RAD_TO_DEG;
        double pct = 100.0 * goal_dps / WHEEL_NO_LOAD_DPS + WHEEL_KP_PCT_PER_DPS * (goal_dps - speed_dps);
        duty = (float)(pct > 100.0 ? 100.0 : pct < -100.0 ? -100.0 : pct);
    }
    io->write_duty(io->ctx, duty);
}

static void write_registers(servo_t *servo, uint8_t address, const uint8_t *data, size_t n) {
    int touched = 0;
    for (size_t i = 0; i < n; i++) {
        unsigned reg = address + (unsigned)i;
        if (reg == OB_SCS_REG_MODE) {
            servo->mode = data[i];
            touched = 1;
        } else if (reg == OB_SCS_REG_TORQUE_ENABLE) {
            servo->torque_on = data[i] != 0;
            touched = 1;
        } else if (reg == OB_SCS_REG_GOAL_TIME) {
            servo->duty_raw = (uint16_t)((servo->duty_raw & 0xFF00u) | data[i]);
            touched = 1;
        } else if (reg == OB_SCS_REG_GOAL_TIME + 1u) {
            servo->duty_raw = (uint16_t)((servo->duty_raw & 0x00FFu) | ((unsigned)data[i] << 8));
            touched = 1;
        } else if (reg == OB_SCS_REG_GOAL_SPEED) {
            servo->speed_raw = (uint16_t)((servo->speed_raw & 0xFF00u) | data[i]);
            touched = 1;
        } else if (reg == OB_SCS_REG_GOAL_SPEED + 1u) {
            servo->speed_raw = (uint16_t)((servo->speed_raw & 0x00FFu) | ((unsigned)data[i] << 8));
            touched = 1;
        }
    }
    if (touched) {
        apply(servo);
    }
}

static void feedback(const servo_t *servo, uint8_t *out) {
    const WheelIOObject *io = servo->wheel;
    double counts = nearbyint(io->sign * *io->wheel->qpos * (COUNTS_PER_REV / (2.0 * 3.14159265358979323846)));
    int32_t window = (int32_t)fmod(counts + 32767.0, (double)MULTI_TURN_SPAN);
    if (window < 0) {
        window += MULTI_TURN_SPAN;
    }
    double steps_per_s = io->sign * *io->wheel->qvel * RAD_TO_DEG * (COUNTS_PER_REV / 360.0);
    double load = io->wheel->coasting ? 0.0 : io->sign * io->wheel->duty * 1000.0;
    ob_scs_put_u16(out, ob_scs_sm_encode(window - 32767, OB_SCS_POSITION_SIGN_BIT));
    ob_scs_put_u16(out + 2, ob_scs_sm_encode((int32_t)lround(steps_per_s), OB_SCS_SPEED_SIGN_BIT));
    ob_scs_put_u16(out + 4, ob_scs_sm_encode((int32_t)lround(load), OB_SCS_LOAD_SIGN_BIT));
}

/* The servo's answer to one request frame, into self->reply (nothing for broadcasts and silence). */
static void execute(ServoWireObject *self, const ob_scs_frame_t *frame) {
    self->packets++;
    if (frame->code == OB_SCS_INSTR_SYNC_WRITE) {
        if (frame->param_len < 2) {
            return;
        }
        uint8_t address = frame->params[0], width = frame->params[1];
        for (size_t i = 2; width > 0 && i + width < frame->param_len + 1u; i += (size_t)width + 1u) {
            servo_t *servo = find(self, frame->params[i]);
            if (servo != NULL && !servo->silent) {
                write_registers(servo, address, &frame->params[i + 1], width);
            }
        }
        return;
    }
    servo_t *servo = find(self, frame->id);
    if (servo == NULL || servo->silent) {
        return;
    }
    uint8_t params[6];
    size_t n = 0;
    if (frame->code == OB_SCS_INSTR_READ) {
        if (frame->param_len != 2 || frame->params[0] != OB_SCS_REG_PRESENT_POSITION || frame->params[1] != 6) {
            return; /* the engine reads nothing else; a real servo would, but no one asks here */
        }
        feedback(servo, params);
        n = 6;
    } else if (frame->code == OB_SCS_INSTR_WRITE) {
        if (frame->param_len < 2) {
            return;
        }
        write_registers(servo, frame->params[0], &frame->params[1], frame->param_len - 1u);
    } else if (frame->code != OB_SCS_INSTR_PING) {
        return;
    }
    int len = ob_scs_encode_status(servo->id, 0, params, n, self->reply, sizeof(self->reply));
    self->reply_len = len > 0 ? (size_t)len : 0u;
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
    self->reply_len = 0;
    ob_scs_frame_t frame;
    size_t offset = 0;
    while (offset < n) {
        ob_scs_parse_t result = ob_scs_parse_frame(data + offset, n - offset, &frame);
        if (result == OB_SCS_PARSE_OK) {
            execute(self, &frame);
        }
        if (frame.consumed == 0 || result == OB_SCS_PARSE_NEED_MORE) {
            break;
        }
        offset += frame.consumed;
    }
    if (self->reply_len > 0) {
        self->reply_done_us = sent + self->return_delay_us + (uint64_t)self->reply_len * self->byte_us;
        self->line_free_us = self->reply_done_us;
        self->line_busy_us += (uint64_t)self->reply_len * self->byte_us;
    }
    return true;
}

static size_t wire_read(void *ctx, uint8_t *buf, size_t cap, uint32_t timeout_us) {
    ServoWireObject *self = ctx;
    uint64_t now = wire_now(self);
    if (self->reply_len == 0 || self->reply_done_us > now + timeout_us) {
        self->clock_us = now + timeout_us; /* waited the whole timeout */
        return 0;
    }
    if (self->reply_done_us > now) {
        self->clock_us = self->reply_done_us;
    }
    size_t n = self->reply_len < cap ? self->reply_len : cap;
    memcpy(buf, self->reply, n);
    memmove(self->reply, self->reply + n, self->reply_len - n);
    self->reply_len -= n;
    return n;
}

static void wire_flush_input(void *ctx) {
    ((ServoWireObject *)ctx)->reply_len = 0;
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
    return 0;
}

static int sw_traverse(ServoWireObject *self, visitproc visit, void *arg) {
    Py_VISIT(self->controller);
    for (int i = 0; i < MAX_SERVOS; i++) {
        Py_VISIT(self->servos[i].wheel);
    }
    return 0;
}

static int sw_clear(ServoWireObject *self) {
    for (int i = 0; i < MAX_SERVOS; i++) {
        self->servos[i].used = 0;
        Py_CLEAR(self->servos[i].wheel);
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
    if (self->controller == NULL || find(self, id) != NULL) {
        PyErr_Format(PyExc_ValueError, "ServoWire.attach: servo id %d is already on the wire", id);
        return NULL;
    }
    for (int i = 0; i < MAX_SERVOS; i++) {
        servo_t *servo = &self->servos[i];
        if (!servo->used) {
            memset(servo, 0, sizeof(*servo));
            servo->used = 1;
            servo->id = id;
            servo->wheel = (WheelIOObject *)Py_NewRef(wheel);
            Py_RETURN_NONE;
        }
    }
    PyErr_Format(PyExc_ValueError, "ServoWire.attach: at most %d servos", MAX_SERVOS);
    return NULL;
}

static PyObject *sw_detach(ServoWireObject *self, PyObject *arg) {
    uint8_t id;
    if (id_arg(arg, &id) < 0) {
        return NULL;
    }
    servo_t *servo = find(self, id);
    if (servo != NULL) {
        servo->used = 0;
        Py_CLEAR(servo->wheel);
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
    servo_t *servo = find(self, id);
    if (servo == NULL) {
        PyErr_Format(PyExc_ValueError, "ServoWire.set_silent: servo id %d is not on the wire", id);
        return NULL;
    }
    servo->silent = silent;
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
                         self->packets, "clock_us", (unsigned long long)self->clock_us);
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
