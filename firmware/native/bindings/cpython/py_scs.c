/*
 * openbricks_native.scs: the serial-bus packet codec for the host.
 *
 * A namespace submodule (also importable as `openbricks_native.scs`) so the
 * short names ping/read/write read as what they are: packet builders that
 * return bytes, and parsers that take any bytes-like receive buffer. Bad
 * arguments raise ValueError naming the argument and its allowed range; bus
 * data never raises, it decodes to a result string instead.
 */
#include "bindings.h"
#include "scs.h"

static PyTypeObject *frame_type;
static PyTypeObject *status_type;

/* Python int -> byte, with a message naming what the value is and what it may be. */
static int scs_byte_arg(PyObject *obj, const char *what, long lo, long hi, uint8_t *out) {
    int overflow = 0;
    long v = PyLong_AsLongAndOverflow(obj, &overflow);
    if (v == -1 && PyErr_Occurred()) {
        return -1;
    }
    if (overflow || v < lo || v > hi) {
        PyErr_Format(PyExc_ValueError, "%s %R is out of range %ld..%ld", what, obj, lo, hi);
        return -1;
    }
    *out = (uint8_t)v;
    return 0;
}

static PyObject *scs_packet(const uint8_t *buf, int n) {
    return PyBytes_FromStringAndSize((const char *)buf, n);
}

/* Which register span was asked for, in the hex the memory table is written in. */
static PyObject *scs_span_error(const char *what, size_t n, uint8_t reg) {
    char msg[128];
    PyOS_snprintf(msg, sizeof msg, "%s of %zu bytes at register 0x%02X runs past register 0xFF", what, n,
                  (unsigned)reg);
    PyErr_SetString(PyExc_ValueError, msg);
    return NULL;
}

/* Codec failures left after the argument checks: report them with the codec's own text. */
static PyObject *scs_codec_error(const char *what, int code) {
    PyErr_Format(PyExc_ValueError, "%s: %s", what, ob_scs_strerror(code));
    return NULL;
}

static PyObject *scs_ping(PyObject *self, PyObject *args, PyObject *kwargs) {
    static char *kwlist[] = {"id", NULL};
    PyObject *id_obj;
    uint8_t id;
    uint8_t out[OB_SCS_MAX_FRAME];
    (void)self;
    if (!PyArg_ParseTupleAndKeywords(args, kwargs, "O:ping", kwlist, &id_obj) ||
        scs_byte_arg(id_obj, "servo id", 0, OB_SCS_BROADCAST_ID, &id) < 0) {
        return NULL;
    }
    int n = ob_scs_encode_ping(id, out, sizeof out);
    return n < 0 ? scs_codec_error("ping", n) : scs_packet(out, n);
}

static PyObject *scs_read(PyObject *self, PyObject *args, PyObject *kwargs) {
    static char *kwlist[] = {"id", "register", "length", NULL};
    PyObject *id_obj, *reg_obj, *len_obj;
    uint8_t id, reg, len;
    uint8_t out[OB_SCS_MAX_FRAME];
    (void)self;
    if (!PyArg_ParseTupleAndKeywords(args, kwargs, "OOO:read", kwlist, &id_obj, &reg_obj, &len_obj) ||
        scs_byte_arg(id_obj, "servo id (a read needs one servo, not broadcast)", 0, OB_SCS_MAX_SERVO_ID,
                     &id) < 0 ||
        scs_byte_arg(reg_obj, "register", 0, 0xFF, &reg) < 0 ||
        scs_byte_arg(len_obj, "read length", 1, OB_SCS_MAX_PARAMS, &len) < 0) {
        return NULL;
    }
    int n = ob_scs_encode_read(id, reg, len, out, sizeof out);
    if (n == OB_SCS_E_REGISTER) {
        return scs_span_error("read", len, reg);
    }
    return n < 0 ? scs_codec_error("read", n) : scs_packet(out, n);
}

static PyObject *scs_write(PyObject *self, PyObject *args, PyObject *kwargs) {
    static char *kwlist[] = {"id", "register", "data", NULL};
    PyObject *id_obj, *reg_obj;
    Py_buffer data;
    uint8_t id, reg;
    uint8_t out[OB_SCS_MAX_FRAME];
    (void)self;
    if (!PyArg_ParseTupleAndKeywords(args, kwargs, "OOy*:write", kwlist, &id_obj, &reg_obj, &data)) {
        return NULL;
    }
    PyObject *result = NULL;
    if (scs_byte_arg(id_obj, "servo id", 0, OB_SCS_BROADCAST_ID, &id) < 0 ||
        scs_byte_arg(reg_obj, "register", 0, 0xFF, &reg) < 0) {
        goto done;
    }
    if (data.len < 1 || data.len > (Py_ssize_t)(OB_SCS_MAX_PARAMS - 1u)) {
        PyErr_Format(PyExc_ValueError, "write data is %zd bytes; it must be 1..%u", data.len,
                     OB_SCS_MAX_PARAMS - 1u);
        goto done;
    }
    int n = ob_scs_encode_write(id, reg, data.buf, (size_t)data.len, out, sizeof out);
    if (n == OB_SCS_E_REGISTER) {
        scs_span_error("write", (size_t)data.len, reg);
    } else {
        result = n < 0 ? scs_codec_error("write", n) : scs_packet(out, n);
    }
done:
    PyBuffer_Release(&data);
    return result;
}

/* Gather (id, data) rows into the codec's parallel id and data arrays. */
static int scs_sync_rows(PyObject *rows_obj, uint8_t *ids, uint8_t *data, size_t *count, uint8_t *data_len) {
    PyObject *rows = PySequence_Fast(rows_obj, "sync_write rows must be a sequence of (id, data) pairs");
    if (rows == NULL) {
        return -1;
    }
    int rc = -1;
    Py_ssize_t n_rows = PySequence_Fast_GET_SIZE(rows);
    if (n_rows < 1 || n_rows > (Py_ssize_t)(OB_SCS_MAX_PARAMS - 2u) / 2) {
        PyErr_Format(PyExc_ValueError, "sync_write has %zd rows; it takes 1..%u servos", n_rows,
                     (OB_SCS_MAX_PARAMS - 2u) / 2u);
        goto done;
    }
    size_t used = 0;
    for (Py_ssize_t i = 0; i < n_rows; i++) {
        PyObject *row = PySequence_Fast_GET_ITEM(rows, i);
        PyObject *id_obj, *bytes_obj;
        if (!PyTuple_Check(row) || PyTuple_GET_SIZE(row) != 2) {
            PyErr_Format(PyExc_TypeError, "sync_write row %zd must be an (id, data) pair, not %R", i, row);
            goto done;
        }
        id_obj = PyTuple_GET_ITEM(row, 0);
        bytes_obj = PyTuple_GET_ITEM(row, 1);
        if (scs_byte_arg(id_obj, "sync_write servo id", 0, OB_SCS_MAX_SERVO_ID, &ids[i]) < 0) {
            goto done;
        }
        Py_buffer view;
        if (PyObject_GetBuffer(bytes_obj, &view, PyBUF_SIMPLE) < 0) {
            goto done;
        }
        if (i == 0) {
            if (view.len < 1 || view.len > 0xFF) {
                PyErr_Format(PyExc_ValueError, "sync_write data for servo %u is %zd bytes; it must be 1..255",
                             (unsigned)ids[i], view.len);
                PyBuffer_Release(&view);
                goto done;
            }
            *data_len = (uint8_t)view.len;
        } else if (view.len != *data_len) {
            PyErr_Format(PyExc_ValueError,
                         "sync_write data for servo %u is %zd bytes but the first row has %u; every servo "
                         "gets the same register span",
                         (unsigned)ids[i], view.len, (unsigned)*data_len);
            PyBuffer_Release(&view);
            goto done;
        }
        if (used + (size_t)view.len > OB_SCS_MAX_PARAMS) {
            PyErr_Format(PyExc_ValueError, "sync_write rows exceed the %u parameter bytes of one packet",
                         OB_SCS_MAX_PARAMS);
            PyBuffer_Release(&view);
            goto done;
        }
        memcpy(data + used, view.buf, (size_t)view.len);
        used += (size_t)view.len;
        PyBuffer_Release(&view);
    }
    *count = (size_t)n_rows;
    rc = 0;
done:
    Py_DECREF(rows);
    return rc;
}

static PyObject *scs_sync_write(PyObject *self, PyObject *args, PyObject *kwargs) {
    static char *kwlist[] = {"register", "rows", NULL};
    PyObject *reg_obj, *rows_obj;
    uint8_t reg, data_len = 0;
    uint8_t ids[OB_SCS_MAX_PARAMS];
    uint8_t data[OB_SCS_MAX_PARAMS];
    size_t count = 0;
    uint8_t out[OB_SCS_MAX_FRAME];
    (void)self;
    if (!PyArg_ParseTupleAndKeywords(args, kwargs, "OO:sync_write", kwlist, &reg_obj, &rows_obj) ||
        scs_byte_arg(reg_obj, "register", 0, 0xFF, &reg) < 0 ||
        scs_sync_rows(rows_obj, ids, data, &count, &data_len) < 0) {
        return NULL;
    }
    int n = ob_scs_encode_sync_write(reg, data_len, ids, data, count, out, sizeof out);
    if (n == OB_SCS_E_LENGTH) {
        return PyErr_Format(PyExc_ValueError,
                            "sync_write of %zu servos x %u bytes exceeds the %u parameter bytes of one packet",
                            count, (unsigned)data_len, OB_SCS_MAX_PARAMS);
    }
    if (n == OB_SCS_E_REGISTER) {
        return scs_span_error("sync_write", data_len, reg);
    }
    return n < 0 ? scs_codec_error("sync_write", n) : scs_packet(out, n);
}

static PyObject *scs_params_packet(const char *name, uint8_t id, uint8_t code, Py_buffer *params,
                                   int is_status) {
    uint8_t out[OB_SCS_MAX_FRAME];
    if (params->len > (Py_ssize_t)OB_SCS_MAX_PARAMS) {
        return PyErr_Format(PyExc_ValueError, "%s params are %zd bytes; a packet holds at most %u", name,
                            params->len, OB_SCS_MAX_PARAMS);
    }
    int n = is_status ? ob_scs_encode_status(id, code, params->buf, (size_t)params->len, out, sizeof out)
                      : ob_scs_encode_frame(id, code, params->buf, (size_t)params->len, out, sizeof out);
    return n < 0 ? scs_codec_error(name, n) : scs_packet(out, n);
}

static PyObject *scs_status(PyObject *self, PyObject *args, PyObject *kwargs) {
    static char *kwlist[] = {"id", "error", "params", NULL};
    PyObject *id_obj, *error_obj = NULL;
    Py_buffer params = {0};
    uint8_t id, error = 0;
    (void)self;
    if (!PyArg_ParseTupleAndKeywords(args, kwargs, "O|Oy*:status", kwlist, &id_obj, &error_obj, &params)) {
        return NULL;
    }
    PyObject *result = NULL;
    if (scs_byte_arg(id_obj, "servo id (a reply comes from one servo)", 0, OB_SCS_MAX_SERVO_ID, &id) == 0 &&
        (error_obj == NULL || scs_byte_arg(error_obj, "error flags", 0, 0xFF, &error) == 0)) {
        result = scs_params_packet("status", id, error, &params, 1);
    }
    if (params.obj != NULL) {
        PyBuffer_Release(&params);
    }
    return result;
}

static PyObject *scs_frame(PyObject *self, PyObject *args, PyObject *kwargs) {
    static char *kwlist[] = {"id", "instruction", "params", NULL};
    PyObject *id_obj, *instr_obj;
    Py_buffer params = {0};
    uint8_t id, instr;
    (void)self;
    if (!PyArg_ParseTupleAndKeywords(args, kwargs, "OO|y*:frame", kwlist, &id_obj, &instr_obj, &params)) {
        return NULL;
    }
    PyObject *result = NULL;
    if (scs_byte_arg(id_obj, "servo id", 0, OB_SCS_BROADCAST_ID, &id) == 0 &&
        scs_byte_arg(instr_obj, "instruction", 0, 0xFF, &instr) == 0) {
        result = scs_params_packet("frame", id, instr, &params, 0);
    }
    if (params.obj != NULL) {
        PyBuffer_Release(&params);
    }
    return result;
}

static const char *scs_result_name(ob_scs_parse_t r) {
    switch (r) {
    case OB_SCS_PARSE_OK:
        return "ok";
    case OB_SCS_PARSE_NEED_MORE:
        return "need_more";
    case OB_SCS_PARSE_BAD_CHECKSUM:
        return "bad_checksum";
    case OB_SCS_PARSE_BAD_HEADER:
        return "bad_header";
    case OB_SCS_PARSE_BAD_LENGTH:
        return "bad_length";
    default:
        return "bad_argument";
    }
}

static PyObject *scs_decode(PyObject *args, PyTypeObject *type, int status, const char *fmt) {
    Py_buffer data;
    if (!PyArg_ParseTuple(args, fmt, &data)) {
        return NULL;
    }
    ob_scs_frame_t f;
    ob_scs_parse_t r = status ? ob_scs_parse_status(data.buf, (size_t)data.len, &f)
                              : ob_scs_parse_frame(data.buf, (size_t)data.len, &f);
    PyBuffer_Release(&data);
    PyObject *fields[6] = {
        PyUnicode_InternFromString(scs_result_name(r)),
        PyLong_FromSize_t(f.consumed),
        PyLong_FromSize_t(f.needed),
        PyLong_FromLong(f.id),
        PyLong_FromLong(f.code),
        /* Copied out: the caller's buffer may be reused for the next read. */
        PyBytes_FromStringAndSize((const char *)f.params, (Py_ssize_t)f.param_len),
    };
    PyObject *out = PyStructSequence_New(type);
    for (int i = 0; i < 6; i++) {
        if (fields[i] == NULL) {
            Py_CLEAR(out);
        }
    }
    for (int i = 0; i < 6; i++) {
        if (out != NULL) {
            PyStructSequence_SET_ITEM(out, i, fields[i]);
        } else {
            Py_XDECREF(fields[i]);
        }
    }
    return out;
}

static PyObject *scs_decode_frame(PyObject *self, PyObject *args) {
    (void)self;
    return scs_decode(args, frame_type, 0, "y*:decode_frame");
}

static PyObject *scs_decode_status(PyObject *self, PyObject *args) {
    (void)self;
    return scs_decode(args, status_type, 1, "y*:decode_status");
}

static PyObject *scs_checksum(PyObject *self, PyObject *args) {
    Py_buffer data;
    (void)self;
    if (!PyArg_ParseTuple(args, "y*:checksum", &data)) {
        return NULL;
    }
    uint8_t sum = ob_scs_checksum(data.buf, (size_t)data.len);
    PyBuffer_Release(&data);
    return PyLong_FromLong(sum);
}

static PyObject *scs_flag_names(PyObject *self, PyObject *args) {
    PyObject *flags_obj;
    uint8_t flags;
    (void)self;
    if (!PyArg_ParseTuple(args, "O:flag_names", &flags_obj) ||
        scs_byte_arg(flags_obj, "error flags", 0, 0xFF, &flags) < 0) {
        return NULL;
    }
    PyObject *names = PyList_New(0);
    if (names == NULL) {
        return NULL;
    }
    for (unsigned bit = 0; bit < 8; bit++) {
        if (!(flags & (1u << bit))) {
            continue;
        }
        const char *name = ob_scs_flag_name(bit);
        PyObject *s = name ? PyUnicode_FromString(name) : PyUnicode_FromFormat("bit%u", bit);
        if (s == NULL || PyList_Append(names, s) < 0) {
            Py_XDECREF(s);
            Py_DECREF(names);
            return NULL;
        }
        Py_DECREF(s);
    }
    PyObject *tuple = PyList_AsTuple(names);
    Py_DECREF(names);
    return tuple;
}

/* Sign-magnitude register values: ints in, two little-endian register bytes out, and back. */
static PyObject *scs_sm_encode(PyObject *args, unsigned sign_bit, const char *fmt) {
    PyObject *value_obj;
    if (!PyArg_ParseTuple(args, fmt, &value_obj)) {
        return NULL;
    }
    long limit = (1L << sign_bit) - 1;
    int overflow = 0;
    long v = PyLong_AsLongAndOverflow(value_obj, &overflow);
    if (v == -1 && PyErr_Occurred()) {
        return NULL;
    }
    if (overflow || v < -limit || v > limit) {
        /* Saturating would silently command a different setpoint than the caller computed. */
        return PyErr_Format(PyExc_ValueError, "%R does not fit a %u-bit sign-magnitude register (-%ld..%ld)",
                            value_obj, sign_bit + 1u, limit, limit);
    }
    uint8_t out[2];
    ob_scs_put_u16(out, ob_scs_sm_encode((int32_t)v, sign_bit));
    return PyBytes_FromStringAndSize((const char *)out, 2);
}

static PyObject *scs_sm_decode(PyObject *args, unsigned sign_bit, const char *fmt) {
    Py_buffer data;
    if (!PyArg_ParseTuple(args, fmt, &data)) {
        return NULL;
    }
    if (data.len != 2) {
        PyErr_Format(PyExc_ValueError, "a 16-bit register value is 2 bytes, got %zd", data.len);
        PyBuffer_Release(&data);
        return NULL;
    }
    int32_t v = ob_scs_sm_decode(ob_scs_get_u16(data.buf), sign_bit);
    PyBuffer_Release(&data);
    return PyLong_FromLong(v);
}

static PyObject *scs_encode_speed(PyObject *self, PyObject *args) {
    (void)self;
    return scs_sm_encode(args, OB_SCS_SPEED_SIGN_BIT, "O:encode_speed");
}

static PyObject *scs_decode_speed(PyObject *self, PyObject *args) {
    (void)self;
    return scs_sm_decode(args, OB_SCS_SPEED_SIGN_BIT, "y*:decode_speed");
}

static PyObject *scs_encode_position(PyObject *self, PyObject *args) {
    (void)self;
    return scs_sm_encode(args, OB_SCS_POSITION_SIGN_BIT, "O:encode_position");
}

static PyObject *scs_decode_position(PyObject *self, PyObject *args) {
    (void)self;
    return scs_sm_decode(args, OB_SCS_POSITION_SIGN_BIT, "y*:decode_position");
}

static PyObject *scs_encode_load(PyObject *self, PyObject *args) {
    (void)self;
    return scs_sm_encode(args, OB_SCS_LOAD_SIGN_BIT, "O:encode_load");
}

static PyObject *scs_decode_load(PyObject *self, PyObject *args) {
    (void)self;
    return scs_sm_decode(args, OB_SCS_LOAD_SIGN_BIT, "y*:decode_load");
}

static PyMethodDef scs_methods[] = {
    {"ping", (PyCFunction)(void (*)(void))scs_ping, METH_VARARGS | METH_KEYWORDS,
     "ping(id) -> bytes\n\nPING packet; id 0..253, or 254 (broadcast: a lone servo answers with its id)."},
    {"read", (PyCFunction)(void (*)(void))scs_read, METH_VARARGS | METH_KEYWORDS,
     "read(id, register, length) -> bytes\n\nREAD packet for length bytes at register from servo id 0..253."},
    {"write", (PyCFunction)(void (*)(void))scs_write, METH_VARARGS | METH_KEYWORDS,
     "write(id, register, data) -> bytes\n\nWRITE packet; id 254 writes every servo (none replies)."},
    {"sync_write", (PyCFunction)(void (*)(void))scs_sync_write, METH_VARARGS | METH_KEYWORDS,
     "sync_write(register, rows) -> bytes\n\nSYNC WRITE packet from (id, data) rows with equal-length data: "
     "every servo applies its own row at the same packet boundary."},
    {"status", (PyCFunction)(void (*)(void))scs_status, METH_VARARGS | METH_KEYWORDS,
     "status(id, error=0, params=b'') -> bytes\n\nA servo's status reply (what a simulated servo sends)."},
    {"frame", (PyCFunction)(void (*)(void))scs_frame, METH_VARARGS | METH_KEYWORDS,
     "frame(id, instruction, params=b'') -> bytes\n\nAny request frame, for instructions without a builder."},
    {"decode_frame", scs_decode_frame, METH_VARARGS,
     "decode_frame(data) -> Frame(result, consumed, needed, id, instruction, params)\n\n"
     "Parse the first frame in a receive buffer. result is 'ok', 'need_more', 'bad_checksum' or "
     "'bad_length'; drop `consumed` bytes before parsing again."},
    {"decode_status", scs_decode_status, METH_VARARGS,
     "decode_status(data) -> Status(result, consumed, needed, id, error, params)\n\n"
     "As decode_frame for servo replies; a reply from the broadcast id is 'bad_header'."},
    {"checksum", scs_checksum, METH_VARARGS,
     "checksum(data) -> int\n\n~sum(data) & 0xFF, over ID through the last parameter."},
    {"flag_names", scs_flag_names, METH_VARARGS,
     "flag_names(error) -> tuple[str, ...]\n\nNames of the set status error bits, e.g. ('voltage', "
     "'overload'); undocumented bits read 'bit4', 'bit6', 'bit7'."},
    {"encode_speed", scs_encode_speed, METH_VARARGS,
     "encode_speed(steps_per_s) -> bytes\n\nGoal-speed register bytes (sign-magnitude, bit 15)."},
    {"decode_speed", scs_decode_speed, METH_VARARGS,
     "decode_speed(data) -> int\n\nPresent-speed register bytes to signed steps/s."},
    {"encode_position", scs_encode_position, METH_VARARGS,
     "encode_position(steps) -> bytes\n\nGoal-position register bytes (sign-magnitude, bit 15)."},
    {"decode_position", scs_decode_position, METH_VARARGS,
     "decode_position(data) -> int\n\nPresent-position register bytes to signed steps."},
    {"encode_load", scs_encode_load, METH_VARARGS,
     "encode_load(tenths_pct) -> bytes\n\nLoad register bytes (sign-magnitude, bit 10, 0.1 % of stall)."},
    {"decode_load", scs_decode_load, METH_VARARGS,
     "decode_load(data) -> int\n\nPresent-load register bytes to signed 0.1 %-of-stall units."},
    {NULL, NULL, 0, NULL},
};

static PyStructSequence_Field frame_fields[] = {
    {"result", "'ok', 'need_more', 'bad_checksum', 'bad_header' or 'bad_length'"},
    {"consumed", "bytes to drop from the front of the buffer before parsing again"},
    {"needed", "on 'need_more', at least this many more bytes are needed"},
    {"id", "servo id of the frame"},
    {"instruction", "instruction byte"},
    {"params", "parameter bytes"},
    {NULL, NULL},
};

static PyStructSequence_Field status_fields[] = {
    {"result", "'ok', 'need_more', 'bad_checksum', 'bad_header' or 'bad_length'"},
    {"consumed", "bytes to drop from the front of the buffer before parsing again"},
    {"needed", "on 'need_more', at least this many more bytes are needed"},
    {"id", "id of the servo that replied"},
    {"error", "status error flags (see flag_names)"},
    {"params", "parameter bytes"},
    {NULL, NULL},
};

static PyStructSequence_Desc frame_desc = {"openbricks_native.scs.Frame", "A parsed request frame.",
                                           frame_fields, 6};
static PyStructSequence_Desc status_desc = {"openbricks_native.scs.Status", "A parsed servo status reply.",
                                            status_fields, 6};

static int scs_add_constants(PyObject *m) {
    static const struct {
        const char *name;
        long value;
    } constants[] = {
        {"BROADCAST_ID", OB_SCS_BROADCAST_ID},
        {"MAX_SERVO_ID", OB_SCS_MAX_SERVO_ID},
        {"PING", OB_SCS_INSTR_PING},
        {"READ", OB_SCS_INSTR_READ},
        {"WRITE", OB_SCS_INSTR_WRITE},
        {"SYNC_WRITE", OB_SCS_INSTR_SYNC_WRITE},
        {"FLAG_VOLTAGE", OB_SCS_FLAG_VOLTAGE},
        {"FLAG_ANGLE", OB_SCS_FLAG_ANGLE},
        {"FLAG_OVERHEAT", OB_SCS_FLAG_OVERHEAT},
        {"FLAG_OVERCURRENT", OB_SCS_FLAG_OVERCURRENT},
        {"FLAG_OVERLOAD", OB_SCS_FLAG_OVERLOAD},
        {"REG_ID", OB_SCS_REG_ID},
        {"REG_RESPONSE_LEVEL", OB_SCS_REG_RESPONSE_LEVEL},
        {"REG_MIN_ANGLE", OB_SCS_REG_MIN_ANGLE},
        {"REG_MAX_ANGLE", OB_SCS_REG_MAX_ANGLE},
        {"REG_MAX_TORQUE", OB_SCS_REG_MAX_TORQUE},
        {"REG_MODE", OB_SCS_REG_MODE},
        {"REG_TORQUE_ENABLE", OB_SCS_REG_TORQUE_ENABLE},
        {"REG_ACCELERATION", OB_SCS_REG_ACCELERATION},
        {"REG_GOAL_POSITION", OB_SCS_REG_GOAL_POSITION},
        {"REG_GOAL_TIME", OB_SCS_REG_GOAL_TIME},
        {"REG_GOAL_SPEED", OB_SCS_REG_GOAL_SPEED},
        {"REG_TORQUE_LIMIT", OB_SCS_REG_TORQUE_LIMIT},
        {"REG_LOCK", OB_SCS_REG_LOCK},
        {"REG_PRESENT_POSITION", OB_SCS_REG_PRESENT_POSITION},
        {"REG_PRESENT_SPEED", OB_SCS_REG_PRESENT_SPEED},
        {"REG_PRESENT_LOAD", OB_SCS_REG_PRESENT_LOAD},
        {"REG_PRESENT_VOLTAGE", OB_SCS_REG_PRESENT_VOLTAGE},
        {"REG_PRESENT_TEMPERATURE", OB_SCS_REG_PRESENT_TEMPERATURE},
        {"REG_MOVING", OB_SCS_REG_MOVING},
        {"REG_PRESENT_CURRENT", OB_SCS_REG_PRESENT_CURRENT},
        {"REG_COUNT", OB_SCS_REG_COUNT},
        {"MODE_POSITION", OB_SCS_MODE_POSITION},
        {"MODE_WHEEL", OB_SCS_MODE_WHEEL},
        {"MODE_DUTY", OB_SCS_MODE_DUTY},
        {"MODE_STEP", OB_SCS_MODE_STEP},
        {"COUNTS_PER_REV", OB_SCS_COUNTS_PER_REV},
        {"MULTI_TURN_SPAN", OB_SCS_MULTI_TURN_SPAN},
        {"POSITION_SIGN_BIT", OB_SCS_POSITION_SIGN_BIT},
        {"SPEED_SIGN_BIT", OB_SCS_SPEED_SIGN_BIT},
        {"LOAD_SIGN_BIT", OB_SCS_LOAD_SIGN_BIT},
        {"DUTY_SIGN_BIT", OB_SCS_DUTY_SIGN_BIT},
    };
    for (size_t i = 0; i < sizeof constants / sizeof constants[0]; i++) {
        if (PyModule_AddIntConstant(m, constants[i].name, constants[i].value) < 0) {
            return -1;
        }
    }
    return 0;
}

int ob_py_add_scs(PyObject *module) {
    PyObject *scs = PyModule_New("openbricks_native.scs");
    if (scs == NULL) {
        return -1;
    }
    if (PyModule_SetDocString(scs, "Feetech SCS/STS serial-bus packet codec (ST-3215, ST-3032).") < 0 ||
        PyModule_AddFunctions(scs, scs_methods) < 0 || scs_add_constants(scs) < 0) {
        goto fail;
    }
    frame_type = PyStructSequence_NewType(&frame_desc);
    status_type = PyStructSequence_NewType(&status_desc);
    if (frame_type == NULL || status_type == NULL ||
        PyModule_AddObjectRef(scs, "Frame", (PyObject *)frame_type) < 0 ||
        PyModule_AddObjectRef(scs, "Status", (PyObject *)status_type) < 0) {
        goto fail;
    }
    /* Registered so `import openbricks_native.scs` works as well as attribute access. */
    if (PyDict_SetItemString(PyImport_GetModuleDict(), "openbricks_native.scs", scs) < 0 ||
        PyModule_AddObjectRef(module, "scs", scs) < 0) {
        goto fail;
    }
    Py_DECREF(scs);
    return 0;
fail:
    Py_DECREF(scs);
    return -1;
}
