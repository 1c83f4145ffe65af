/*
 * Argument checks shared by the host bindings, so every binding rejects bad
 * input the same way: a TypeError or ValueError that names the callable and
 * the argument, and says what would be accepted.
 */
#ifndef OB_PY_ARGS_H
#define OB_PY_ARGS_H

#include <math.h>
#include <string.h>

#include "bindings.h"
#include "ob_types.h"

/* Number-like objects other than int and float (numpy scalars, Fraction, ...)
 * convert through __float__ / __index__; str and bool never count as numbers. */
static inline int ob_py_is_number(PyObject *obj) {
    if (PyFloat_Check(obj) || (PyLong_Check(obj) && !PyBool_Check(obj))) {
        return 1;
    }
    PyNumberMethods *nb = Py_TYPE(obj)->tp_as_number;
    return !PyBool_Check(obj) && nb != NULL && (nb->nb_float != NULL || nb->nb_index != NULL);
}

/* A real, finite number that fits a float. 0 on success. */
static inline int ob_py_float(PyObject *obj, const char *where, const char *name, float *out) {
    if (!ob_py_is_number(obj)) {
        PyErr_Format(PyExc_TypeError, "%s: %s must be a number, not %.100s", where, name,
                     Py_TYPE(obj)->tp_name);
        return -1;
    }
    double value = PyFloat_AsDouble(obj);
    if (value == -1.0 && PyErr_Occurred()) {
        return -1;
    }
    if (!isfinite(value) || fabs(value) > 3.0e38) {
        PyErr_Format(PyExc_ValueError, "%s: %s must be a finite number, got %R", where, name, obj);
        return -1;
    }
    *out = (float)value;
    return 0;
}

/* As ob_py_float, and > 0. */
static inline int ob_py_positive_float(PyObject *obj, const char *where, const char *name, float *out) {
    if (ob_py_float(obj, where, name, out) < 0) {
        return -1;
    }
    if (!(*out > 0.0f)) {
        PyErr_Format(PyExc_ValueError, "%s: %s must be > 0, got %R", where, name, obj);
        return -1;
    }
    return 0;
}

/* A scheduler time: a non-negative int, taken modulo 2^32 like the hub's tick clock. */
static inline int ob_py_time_ms(PyObject *obj, const char *where, uint32_t *out) {
    PyObject *index = NULL;
    if (!PyLong_Check(obj) || PyBool_Check(obj)) {
        /* Integer-like objects (numpy ints) via __index__; floats are refused, not truncated. */
        PyNumberMethods *nb = Py_TYPE(obj)->tp_as_number;
        if (PyBool_Check(obj) || nb == NULL || nb->nb_index == NULL) {
            PyErr_Format(PyExc_TypeError, "%s: now_ms must be an int (milliseconds), not %.100s", where,
                         Py_TYPE(obj)->tp_name);
            return -1;
        }
        index = PyNumber_Index(obj);
        if (index == NULL) {
            return -1;
        }
        obj = index;
    }
    int overflow = 0;
    long long value = PyLong_AsLongLongAndOverflow(obj, &overflow);
    int failed = value == -1 && PyErr_Occurred();
    if (!failed && (overflow != 0 || value < 0)) {
        PyErr_Format(PyExc_ValueError, "%s: now_ms must be within 0..2**63-1, got %R", where, obj);
        failed = 1;
    }
    Py_XDECREF(index);
    if (failed) {
        return -1;
    }
    *out = (uint32_t)value;
    return 0;
}

/* The manual's then= strings. */
static inline int ob_py_then(PyObject *obj, const char *where, ob_then_t *out) {
    static const struct {
        const char *name;
        ob_then_t then;
    } names[] = {
        {"coast", OB_THEN_COAST}, {"stop", OB_THEN_COAST},         {"brake", OB_THEN_BRAKE},
        {"hold", OB_THEN_HOLD},   {"continue", OB_THEN_CONTINUE},
    };
    if (!PyUnicode_Check(obj)) {
        PyErr_Format(PyExc_TypeError,
                     "%s: then must be one of 'coast', 'stop', 'brake', 'hold', 'continue', not %.100s", where,
                     Py_TYPE(obj)->tp_name);
        return -1;
    }
    const char *text = PyUnicode_AsUTF8(obj);
    if (text == NULL) {
        return -1;
    }
    for (size_t i = 0; i < sizeof(names) / sizeof(names[0]); i++) {
        if (strcmp(text, names[i].name) == 0) {
            *out = names[i].then;
            return 0;
        }
    }
    PyErr_Format(PyExc_ValueError, "%s: then must be one of 'coast', 'stop', 'brake', 'hold', 'continue', got %R",
                 where, obj);
    return -1;
}

/* Canonical name of a then value, for reporting state. */
static inline const char *ob_py_then_name(ob_then_t then) {
    switch (then) {
    case OB_THEN_BRAKE:
        return "brake";
    case OB_THEN_HOLD:
        return "hold";
    case OB_THEN_CONTINUE:
        return "continue";
    case OB_THEN_COAST:
    default:
        return "coast";
    }
}

#endif /* OB_PY_ARGS_H */
