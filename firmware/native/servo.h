/*
 * Closed-loop control of one motor with an angle sensor (pbio servo.c and
 * control.c in spirit): speed runs, position moves and hold on trapezoidal
 * trajectories, open-loop duty, brake and coast, stall detection, and a safe
 * halt when the angle feedback goes silent.
 *
 * Every closed-loop command tracks a trajectory sampled at the scheduler's
 * measured clock, so a late tick costs one control update but never stretches
 * the move. The control law is control.h's, feed-forward from the reference
 * (speed, acceleration, static friction) plus feedback:
 *
 *   speed runs      duty = ff + speed_kp * (v_ref - v) + speed_ki * (x_ref - x)
 *                   The position term is the integral of the speed error. When
 *                   the motor cannot follow (blocked, duty-limited) the
 *                   reference position is dragged along so that term never
 *                   asks for more than the duty limit: no windup, and the
 *                   motor does not race to catch up once released.
 *   position moves  duty = ff + kp * (x_ref - x) + kd * (v_ref - v) + ki * I
 *                   I follows control.h's integrator rules, restarting at zero
 *                   with every new command.
 *
 * Units: degrees, deg/s, deg/s^2 at the output shaft; duty in percent.
 */
#ifndef OB_SERVO_H
#define OB_SERVO_H

#include <stdbool.h>
#include <stdint.h>

#include "control.h"
#include "ob_types.h"
#include "observer.h"
#include "trajectory.h"

typedef enum {
    OB_SERVO_COAST = 0,    /* output released */
    OB_SERVO_BRAKE = 1,    /* duty 0: the bridge shorts the winding */
    OB_SERVO_DUTY = 2,     /* open-loop duty (dc) */
    OB_SERVO_SPEED = 3,    /* run at a speed (speed loop on a ramp) */
    OB_SERVO_POSITION = 4, /* run_target / run_angle / hold (position loop) */
} ob_servo_mode_t;

typedef struct {
    /* Position loop. */
    float kp_pct_per_deg;
    float ki_pct_per_deg_s;
    float kd_pct_per_dps;
    float integral_band_deg;  /* errors are clipped to this before they are integrated */
    float integral_limit_pct; /* clamp on the integral's share of the duty */
    /* Speed loop. */
    float speed_kp_pct_per_dps;
    float speed_ki_pct_per_deg;
    /* Feed-forward from the reference: speed, acceleration, and a static term
     * against Coulomb friction in the direction of the reference speed. */
    float ff_pct_per_dps;
    float ff_pct_per_dps2;
    float ff_static_pct;
    /* Motion limits; speed_dps caps every command's speed. */
    float max_speed_dps;
    float accel_dps2;
    float decel_dps2;
    float duty_limit_pct;
    /* When a move counts as done: within tolerance of the target, nearly still. */
    float position_tolerance_deg;
    float speed_tolerance_dps;
    /* Stall: pushing (duty at the limit, or tracking error above
     * stall_error_deg) while slower than stall_speed_dps for stall_time_ms. */
    float stall_error_deg;
    float stall_speed_dps;
    uint32_t stall_time_ms;
    /* Feedback: after silent_timeout_ms without a fresh angle, coast and latch
     * feedback_lost until the next command. */
    uint32_t silent_timeout_ms;
    /* Encoder resolution, for the integrator's dead band (half a count). */
    float counts_per_rev;
    float observer_alpha;
    float observer_beta;
} ob_servo_config_t;

typedef struct {
    ob_motor_io_t io;
    ob_servo_config_t cfg;
    ob_observer_t observer;
    ob_trajectory_t trajectory;

    ob_servo_mode_t mode;
    ob_then_t then;           /* what a position move does when it ends */
    /* The closed-loop command being run, kept so a command given before the
     * first angle reading can be planned once that reading arrives. */
    bool needs_plan;
    bool cmd_relative;        /* cmd_value_deg is relative to the start (run_angle) */
    float cmd_speed_dps;
    float cmd_value_deg;
    float cmd_accel_dps2;
    float cmd_decel_dps2;
    bool plan_unconfirmed;    /* planned from the last tick's state; no fresh reading has confirmed it */
    bool reset_pending;       /* reset_angle before the first reading */
    float reset_to_deg;
    uint32_t start_ms;        /* scheduler time of the trajectory's t = 0 */
    float ref_offset_deg;     /* speed runs: how far the reference was dragged back */
    ob_control_gains_t position_gains; /* the configuration's, as control.h takes them */
    ob_control_gains_t speed_gains;    /* the speed loop as a PD on position: kp = speed_ki, kd = speed_kp */
    ob_integrator_t integrator;        /* position loop */
    float duty_cmd_pct;       /* open-loop duty (dc) */
    float duty_limit_pct;     /* active duty cap (<= 100) */

    /* Last tick. */
    uint32_t now_ms;
    bool clock_valid;         /* a tick has happened since init */
    bool have_angle;          /* a reading has been seen since init */
    float angle_deg;          /* last measured angle, in the user frame */
    float offset_deg;         /* user angle = sensor angle + offset_deg */
    ob_output_t output;       /* what the motor was told last */
    ob_trajectory_sample_t ref;

    /* Status. */
    bool done;
    bool stalled;
    uint32_t stall_since_ms;
    bool stall_timing;
    bool feedback_lost;       /* latched until the next command: the angle went silent
                               * during a closed-loop command, which was halted (coast) */
    uint32_t last_read_ms;    /* time of the last fresh angle */
    uint32_t failed_reads;    /* total failed reads since init */
    uint32_t silent_ticks;    /* consecutive failed reads */

    ob_period_t period;       /* the tick spacing, for the usual, unchanging case */
    /* Speed runs: the position term alone reaches the duty cap here (configuration and cap only). */
    float speed_error_max_deg;
} ob_servo_t;

/* Defaults for an ST-3032-class geared servo (888 deg/s no load, ~1 N*m
 * stall) on a 4096-count encoder ticked at 1 kHz, carrying half of a 1 kg
 * robot: speed 500 deg/s, acceleration 1500 deg/s^2 (the manual's run_angle
 * default). */
void ob_servo_config_default(ob_servo_config_t *cfg);

/* The IO of a servo stepped directly: nothing to read (ob_servo_step is handed
 * each reading) and nothing to write (the caller reads ob_servo_duty_out back). */
extern const ob_motor_io_t ob_servo_direct_io;

/* Start coasting, with no angle seen yet. cfg is copied. */
void ob_servo_init(ob_servo_t *s, const ob_motor_io_t *io, const ob_servo_config_t *cfg);

/* Commands. They plan from the current reference (or the measured state when
 * coming from an open-loop mode) and start at the time of the last tick. */
void ob_servo_run_speed(ob_servo_t *s, float speed_dps);
void ob_servo_run_target(ob_servo_t *s, float speed_dps, float target_deg, ob_then_t then);
/* Relative move; direction is sign(speed_dps) * sign(angle_deg), as in Pybricks. */
void ob_servo_run_angle(ob_servo_t *s, float speed_dps, float angle_deg, ob_then_t then);
/* A position move with its own acceleration and deceleration (magnitudes):
 * to value_deg, or by value_deg (with run_angle's direction rule) when relative. */
void ob_servo_move(ob_servo_t *s, float speed_dps, float value_deg, bool relative, ob_then_t then,
                   float accel_dps2, float decel_dps2);
void ob_servo_hold(ob_servo_t *s);
void ob_servo_dc(ob_servo_t *s, float duty_pct);
void ob_servo_brake(ob_servo_t *s);
void ob_servo_coast(ob_servo_t *s);
/* then= flavour of an immediate stop: coast, brake or hold (continue coasts). */
void ob_servo_stop(ob_servo_t *s, ob_then_t then);

/* Re-zero the user frame: the angle now reads angle_deg. An active move or
 * hold is shifted with it, so the motor does not jump. */
void ob_servo_reset_angle(ob_servo_t *s, float angle_deg);

/* Cap |duty| to limit_pct (clamped to 0..100); stall detection scales with it. */
void ob_servo_set_duty_limit(ob_servo_t *s, float limit_pct);

/* Apply a new configuration (gains, limits); the active command continues. */
void ob_servo_configure(ob_servo_t *s, const ob_servo_config_t *cfg);

/* One control update with the sensor reading already in hand (have_angle false
 * when the read failed). ob_servo_tick reads io.read_angle and calls this. */
void ob_servo_step(ob_servo_t *s, uint32_t now_ms, bool have_angle, float sensor_deg);

/* Scheduler subscriber: read the angle through io, update, write the output. */
void ob_servo_tick(void *servo, uint32_t now_ms);

/* A position move has ended (on target or stalled), or no closed-loop move is
 * active. Speed runs are never done; then="continue" moves are done once the
 * target is passed. */
static inline bool ob_servo_is_done(const ob_servo_t *s) {
    return s->done;
}

static inline bool ob_servo_is_stalled(const ob_servo_t *s) {
    return s->stalled;
}

/* Last measured angle and the observer's speed estimate, in the user frame. */
static inline float ob_servo_angle_deg(const ob_servo_t *s) {
    return s->angle_deg;
}

static inline float ob_servo_speed_dps(const ob_servo_t *s) {
    return s->observer.v_dps;
}

/* The duty written last, or false while the output is released (coasting). */
static inline bool ob_servo_duty_out(const ob_servo_t *s, float *duty_pct) {
    *duty_pct = s->output.duty_pct;
    return !s->output.coasting;
}

#endif /* OB_SERVO_H */
