/*
 * What the files of openbricks_mjcontrol share: the controller of the simulated motors and the
 * native wheel IO onto one of them (mjcontrol.c), which the emulated servo bus (servo_wire.c)
 * drives in C.
 */
#ifndef OB_SIM_MJCONTROL_H
#define OB_SIM_MJCONTROL_H

#define PY_SSIZE_T_CLEAN
#include <Python.h>
#include <stdint.h>

#include "ob_types.h"
#include "py_capi.h"
#include "py_motor_io.h"

#define MAX_WHEELS 8
#define RAD_TO_DEG (180.0 / 3.14159265358979323846)

/* MuJoCo's void mj_step(const mjModel *m, mjData *d), found in its library at run time: this
 * extension does not link MuJoCo, whose Python package carries the one library every part uses. */
typedef void (*mj_step_fn)(const void *model, void *data);

/* A long Controller.step() lets other Python threads (a viewer, a pacer) run this often. */
#define STEPS_PER_GIL_RELEASE 50

typedef struct {
    const double *qpos; /* joint angle, rad, inside mjData */
    const double *qvel; /* joint speed, rad/s */
    double *ctrl;       /* the joint's torque actuator, N m */
    double stall_torque_nm;
    double inv_no_load_rad_s;
    double torque_scale; /* 1.0; below 1 models a weak motor or a dragging gearbox */
    int coasting;
    double duty; /* -1..1 in the joint frame; duty 0 shorts the winding (brake) */
    double torque_nm; /* written last step */
} wheel_t;

typedef struct {
    PyObject_HEAD
    PyObject *model;
    PyObject *data;
    PyObject *world; /* MotorProcess of the simulated devices, or NULL */
    void *model_address;   /* mjModel * */
    void *data_address;    /* mjData * */
    mj_step_fn mj_step;    /* MuJoCo's own C mj_step */
    double *qpos, *qvel, *ctrl;
    Py_ssize_t nq, nv, nu;
    wheel_t wheels[MAX_WHEELS];
    int n_wheels;
    uint64_t now_ms; /* simulated milliseconds: one per controlled step */
    long armed;      /* steps the callback may still run in the current step() */
    PyObject *error_type, *error_value, *error_tb; /* first tick error of the current step() */
} ControllerObject;

typedef struct {
    ob_py_motor_io_t base;
    ControllerObject *owner;
    wheel_t *wheel;
    int index;
    double sign;          /* +1: this IO's positive is the joint's positive */
    double counts_per_rad;
    double deg_per_count;
    int silent;           /* an unplugged motor: no readings, commands ignored */
    unsigned long replies;
    unsigned long failed;
    unsigned long failed_in_a_row;
} WheelIOObject;

/* openbricks_mjcontrol.WheelIO (mjcontrol.c). */
extern PyTypeObject WheelIOType;

/* Adds ServoWire, the emulated serial bus (servo_wire.c). */
int ob_sim_add_servo_wire(PyObject *module);

#endif /* OB_SIM_MJCONTROL_H */
