/*
 * Two-wheel differential drivebase: two coupled controllers in (sum,
 * difference) coordinates (pbio drivebase.c in spirit).
 *
 * Coordinates, all in wheel-degrees so one set of gains fits both axes:
 *   sum  s = (left + right) / 2   forward progress of the axle centre
 *   diff d = (left - right) / 2   body rotation; positive = turning right
 * A body heading of h degrees (clockwise from above) is d = h * track / D.
 *
 * Each axis follows its own trajectory with control.h's law (PID +
 * feed-forward, one set of integrator rules); the duties are
 * left = u_s + u_d and right = u_s - u_d. When the sum of the two exceeds the
 * duty range, the heading loop keeps its authority and forward progress is
 * what gives way, so a weak or dragging wheel slows the robot down rather
 * than turning it.
 *
 * Both wheels are "positive = forward": inverting a mirrored motor is the
 * business of whoever builds the ob_motor_io_t.
 *
 * Time: every command starts its trajectories at the clock of the last tick,
 * so commands are issued between ticks and never need the clock themselves.
 */
#ifndef OB_DRIVEBASE_H
#define OB_DRIVEBASE_H

#include <stdbool.h>
#include <stdint.h>

#include "control.h"
#include "observer.h"
#include "ob_types.h"
#include "trajectory.h"

/* Settings defaults, wheel-deg/s and wheel-deg/s^2 (manual 7.1). */
#define OB_DB_DEFAULT_STRAIGHT_SPEED_DPS 360.0f
#define OB_DB_DEFAULT_TURN_RATE_DPS 360.0f
#define OB_DB_DEFAULT_ACCELERATION_DPS2 1500.0f
#define OB_DB_DEFAULT_TURN_ACCELERATION_DPS2 1500.0f

/* A wheel (or the gyro, while steering by it) silent for longer than this halts the drivebase. */
#define OB_DB_DEFAULT_WATCHDOG_MS 20u

/*
 * Gyro heading source: body heading in degrees, clockwise from above
 * positive, in any fixed frame (the drivebase keeps its own zero). Returns
 * false when no fresh reading is available this tick.
 *
 * It is a function pointer rather than a value fed between ticks so the
 * firmware's native tick can read the IMU itself with no Python in the loop;
 * a host that already holds the value passes it to ob_drivebase_step instead.
 */
typedef struct {
    bool (*read_heading)(void *ctx, float *heading_deg);
    void *ctx;
} ob_heading_source_t;

/* End-of-move tolerances, the landing threshold and the lag that pauses a move. */
typedef struct {
    float position_deg;       /* both axes within this of target ... */
    float speed_dps;          /* ... and slower than this: the move is done */
    float landing_deg;        /* residual above this when a profile expires gets a landing trajectory */
    float pause_lag_deg;      /* an axis pinned at the duty limit this far behind pauses the trajectories */
} ob_drivebase_tolerances_t;

/*
 * One axis: its trajectory, controller state, and what the current command
 * asked of it, so that a landing can re-plan the rest of the command from
 * wherever the robot really is.
 */
typedef struct {
    ob_trajectory_t trajectory;
    ob_control_gains_t gains;
    ob_integrator_t integrator;
    float target_deg;         /* positional commands: where this axis ends */
    float speed_dps;          /* positional: cruise speed (magnitude); speed commands: the speed to keep */
    float accel_dps2;         /* acceleration of the command on this axis */
} ob_drivebase_axis_t;

typedef enum {
    OB_DB_IDLE = 0,     /* outputs released (coast) */
    OB_DB_BRAKED,       /* outputs at zero duty: passive brake */
    OB_DB_MOVE,         /* straight / turn / curve, including landing and the then="continue" tail */
    OB_DB_SPEED,        /* drive / move_wheels: speed ramps, then constant speed */
    OB_DB_STOPPING,     /* stop(brake | hold): decelerating */
    OB_DB_HOLD,         /* holding a position */
    OB_DB_FAULT,        /* halted by the watchdog; outputs released */
} ob_drivebase_mode_t;

/* Fault bits: which feedback went silent. */
#define OB_DB_FAULT_LEFT 0x01u
#define OB_DB_FAULT_RIGHT 0x02u
#define OB_DB_FAULT_GYRO 0x04u

enum { OB_DB_LEFT = 0, OB_DB_RIGHT = 1 };

/* Feedback for one control step; *_ok false means no fresh reading this tick. */
typedef struct {
    bool wheel_ok[2];
    float wheel_deg[2];
    bool heading_ok;
    float heading_deg;
} ob_drivebase_feedback_t;

/* Actuation from one control step: coast[i] releases wheel i, else duty_pct[i] applies. */
typedef struct {
    float duty_pct[2];
    bool coast[2];
} ob_drivebase_output_t;

/* Odometry and motion in the drivebase's frame (Pybricks DriveBase.state()). */
typedef struct {
    float distance_mm;
    float drive_speed_mm_s;
    float angle_deg;
    float turn_rate_dps;
} ob_drivebase_state_t;

typedef struct {
    ob_motor_io_t io[2];
    ob_heading_source_t heading_source;
    bool use_gyro;

    /* Geometry. */
    float wheel_diameter_mm;
    float axle_track_mm;
    float deg_per_mm;         /* wheel-deg per mm of travel */
    float diff_per_heading;   /* diff wheel-deg per body-deg */

    /* Settings (wheel-deg/s, wheel-deg/s^2). */
    float straight_speed_dps;
    float turn_rate_dps;
    float acceleration_dps2;
    float turn_acceleration_dps2;

    ob_drivebase_tolerances_t tolerances;
    uint32_t watchdog_ms;

    /* Estimation. */
    ob_observer_t observer[2];
    bool wheel_seen[2];
    uint32_t wheel_last_ms[2];
    float sum_zero_deg;       /* encoder frame: s = (xl + xr) / 2 - sum_zero */
    float diff_zero_deg;      /* encoder frame: d = (xl - xr) / 2 - diff_zero */
    float heading_zero_deg;   /* gyro frame: d = (heading - heading_zero) * diff_per_heading */
    bool heading_aligned;     /* heading_zero matches the frame in use */
    float gyro_diff_deg;      /* last gyro-derived diff, and the encoder diff it was taken at, */
    float gyro_enc_diff_deg;  /* so a missed gyro sample is bridged by the encoder increment */
    uint32_t heading_last_ms;

    /* Measured coordinates as of the last step. */
    float sum_deg, sum_dps;
    float diff_deg, diff_dps;

    /* Control. */
    ob_drivebase_axis_t sum;
    ob_drivebase_axis_t diff;
    ob_drivebase_mode_t mode;
    ob_then_t then;
    bool done;
    bool settling;            /* the move's profile expired; waiting for the tolerances */
    bool plan_unconfirmed;    /* a command planned from the last step's state, no fresh feedback since */
    float plan_sum_deg;       /* ... and the (sum, diff) it planned from */
    float plan_diff_deg;
    uint32_t landings;        /* landing trajectories planned for the current command */
    uint32_t pinned_ms;       /* how long the trajectories have been paused for a robot that cannot follow */
    uint32_t start_ms;        /* clock at which the current trajectories start */
    uint32_t now_ms;
    bool clock_started;
    uint8_t fault;
    ob_drivebase_output_t output;
    ob_output_t written[2];   /* what the tick last wrote through io, per wheel */
    ob_period_t period;       /* the tick spacing, for the usual, unchanging case */
} ob_drivebase_t;

/* Gains of either axis that suit a small geared DC motor or serial-bus servo in duty mode at 1 kHz. */
void ob_drivebase_default_gains(ob_control_gains_t *gains);

/*
 * Set up a drivebase, idle and coasting. Returns false (and leaves db
 * unusable) when a dimension is not a positive finite number.
 */
bool ob_drivebase_init(ob_drivebase_t *db, const ob_motor_io_t *left, const ob_motor_io_t *right,
                       float wheel_diameter_mm, float axle_track_mm);

/* Returns false and changes nothing unless every value is positive and finite. */
bool ob_drivebase_settings(ob_drivebase_t *db, float straight_speed_dps, float turn_rate_dps,
                           float acceleration_dps2, float turn_acceleration_dps2);

/* Replace one axis' gains (sum: forward, diff: heading). */
void ob_drivebase_set_gains(ob_drivebase_t *db, bool heading_axis, const ob_control_gains_t *gains);

/*
 * Moves. Each supersedes whatever was running and starts from the current
 * reference when the controller is active (so chained moves are seamless),
 * or from the measured state when it was idle. They return false, changing
 * nothing, for non-finite arguments and for ones whose wheel-degrees overflow
 * float.
 *
 * straight: forward distance_mm at straight_speed; heading held.
 * turn: angle_deg of body heading at turn_rate, in place. then="continue"
 *   has no speed to carry: the turn ends at rest and holds its heading.
 * curve: along a circle of |radius_mm|, heading changing by angle_deg;
 *   radius sign = travel direction. Centre speed and acceleration are scaled
 *   by |R| / (|R| + track/2) so the outer wheel never exceeds the settings.
 *   A zero radius is a turn in place.
 */
bool ob_drivebase_straight(ob_drivebase_t *db, float distance_mm, ob_then_t then);
bool ob_drivebase_turn(ob_drivebase_t *db, float angle_deg, ob_then_t then);
bool ob_drivebase_curve(ob_drivebase_t *db, float radius_mm, float angle_deg, ob_then_t then);

/*
 * Speed commands, with no end: forward speed and body turn rate, or one
 * speed per wheel. The change ramps so that neither wheel accelerates faster
 * than the acceleration setting and both finish together (an arc keeps its
 * radius through the ramp). done() turns true when the ramp is over.
 */
bool ob_drivebase_drive(ob_drivebase_t *db, float speed_mm_s, float turn_rate_dps);
bool ob_drivebase_move_wheels(ob_drivebase_t *db, float left_dps, float right_dps);

/*
 * Stop. coast releases both wheels at once. brake and hold decelerate both
 * wheels together at the acceleration setting; then brake leaves zero duty
 * and hold anchors where the robot actually came to rest. continue is
 * treated as hold: a stop has no cruise to carry.
 */
void ob_drivebase_stop(ob_drivebase_t *db, ob_then_t then);

/*
 * Re-zero distance and heading: the current pose becomes (0 mm, 0 deg) in
 * the encoder frame and the gyro frame together, and a held position moves
 * with the frame so nothing jumps. Refused (false) while a move is in
 * progress, i.e. while done() is false.
 */
bool ob_drivebase_reset(ob_drivebase_t *db);

/*
 * Steer by a gyro (source non-NULL) or by the encoder difference (NULL). The
 * switch is seamless: the new source's frame is aligned to the old one at the
 * first tick that has a reading. With the gyro in use, ob_drivebase_tick
 * reads the source; ob_drivebase_step takes the heading from its feedback.
 */
void ob_drivebase_use_gyro(ob_drivebase_t *db, const ob_heading_source_t *source);

/* Also true after a coast stop and after a watchdog halt (see ob_drivebase_fault). */
bool ob_drivebase_done(const ob_drivebase_t *db);

/* OB_DB_FAULT_* bits of the last watchdog halt; cleared by the next command. */
uint8_t ob_drivebase_fault(const ob_drivebase_t *db);

void ob_drivebase_get_state(const ob_drivebase_t *db, ob_drivebase_state_t *state);

/*
 * One control step from given feedback: no IO. The host's fast path and the
 * tick below both come through here.
 */
void ob_drivebase_step(ob_drivebase_t *db, uint32_t now_ms, const ob_drivebase_feedback_t *feedback,
                       ob_drivebase_output_t *output);

/* Scheduler subscriber (ob_tick_fn_t): read both wheels (and the gyro), step, write both wheels. */
void ob_drivebase_tick(void *db, uint32_t now_ms);

#endif /* OB_DRIVEBASE_H */
