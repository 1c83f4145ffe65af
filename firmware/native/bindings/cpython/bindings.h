/*
 * The host binding is one extension module, openbricks_native, assembled from
 * one source file per core. Each file adds its types and functions to the
 * module; module.c only calls them in order.
 */
#ifndef OB_PY_BINDINGS_H
#define OB_PY_BINDINGS_H

#define PY_SSIZE_T_CLEAN
#include <Python.h>

int ob_py_add_trajectory(PyObject *module);
int ob_py_add_observer(PyObject *module);
int ob_py_add_scheduler(PyObject *module);
int ob_py_add_servo(PyObject *module);
int ob_py_add_drivebase(PyObject *module);
int ob_py_add_scs(PyObject *module);
int ob_py_add_imu_yaw(PyObject *module);
int ob_py_add_encoder(PyObject *module);
int ob_py_add_icm45686(PyObject *module);
/* HBridge; needs MotorIO and PCNTEncoder added first. */
int ob_py_add_hbridge(PyObject *module);
/* MotorIO and the _C_API capsule; needs the scheduler added first. */
int ob_py_add_capi(PyObject *module);
/* SerialBus and serial_bus(); needs the scheduler and MotorIO added first. */
int ob_py_add_serial_bus(PyObject *module);

#include "drivebase.h"
#include "imu_yaw.h"
/* seed_bias(bias_dps) of an ImuYaw or an ICM45686, which holds one (py_imu_yaw.c). */
PyObject *ob_py_imu_yaw_seed_bias(ob_imu_yaw_t *yaw, PyObject *args);
/* 1 and *source filled when obj is an openbricks_native.ICM45686 (a DriveBase reads its heading in C). */
int ob_py_icm45686_heading_source(PyObject *obj, ob_heading_source_t *source);

#include "encoder.h"
/* The encoder core of an open openbricks_native.PCNTEncoder, or NULL (py_encoder.c): an H-bridge's
 * motor_io() reads it in C. */
ob_encoder_t *ob_py_pcnt_encoder_get(PyObject *obj);

/* motor_process.hard_tick_count() / hard_tick_selftest(duration_ms=100) (py_hard_tick.c). */
PyObject *ob_py_hard_tick_count(PyObject *self, PyObject *unused);
PyObject *ob_py_hard_tick_selftest(PyObject *self, PyObject *args, PyObject *kwargs);

#endif /* OB_PY_BINDINGS_H */
