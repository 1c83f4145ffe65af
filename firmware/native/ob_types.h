/*
 * Shared contract types of the openbricks control cores.
 *
 * The cores are plain C99 with no dependencies so the same files compile into
 * the ESP32 firmware (single-precision FPU: every hot-path quantity is float)
 * and into the host extension that the simulator and the tests use.
 *
 * Units follow the manual: angles in degrees, speeds in deg/s, accelerations
 * in deg/s^2, time in milliseconds on the scheduler clock, duty in percent
 * (-100..100). The drivebase works in wheel-degrees.
 */
#ifndef OB_TYPES_H
#define OB_TYPES_H

#include <stdbool.h>
#include <stdint.h>

/*
 * How a motor's feedback and actuator are reached. The cores never know what
 * is behind these: a PCNT encoder and a PWM pin on the hub, a serial-bus slot,
 * a simulated wheel, or a plant model in a test.
 *
 * read_angle returns false when no fresh reading is available (a silent bus,
 * an unplugged sensor); controllers must then not treat the stale angle as
 * truth. write_duty takes -100..100 percent; write_coast releases the output.
 */
typedef struct {
    bool (*read_angle)(void *ctx, float *angle_deg);
    void (*write_duty)(void *ctx, float duty_pct);
    void (*write_coast)(void *ctx);
    void *ctx;
} ob_motor_io_t;

/* End state of a move: the manual's then= values. */
typedef enum {
    OB_THEN_COAST = 0,    /* "coast", "stop": release torque at the end */
    OB_THEN_BRAKE = 1,    /* "brake": actively resist motion at zero speed */
    OB_THEN_HOLD = 2,     /* "hold": hold the end position */
    OB_THEN_CONTINUE = 3, /* "continue": end at cruise speed and keep it */
} ob_then_t;

#endif /* OB_TYPES_H */
