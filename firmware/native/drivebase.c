/*
 * Two-wheel differential drivebase: coupled (sum, diff) control. See drivebase.h.
 */
#include "drivebase.h"

#include <math.h>
#include <stddef.h>

#define OB_DB_PI 3.14159265358979f
#define OB_DB_MAX_DUTY 100.0f

/* A tick spacing longer than this is a stall of the caller, not elapsed control time: the
 * integrators never integrate over more than this in one step. */
#define OB_DB_MAX_DT_S 0.05f

/* Below this the non-moving axis of a new move counts as at rest and is simply held. */
#define OB_DB_REST_DPS 1.0f

/*
 * A robot pinned (trajectories paused) for at least this long that then moves
 * faster than OB_DB_RELEASE_DPS, or stops being pinned, has been released: the
 * rest of its command is re-planned from where it is.
 */
#define OB_DB_PINNED_MIN_MS 20u
#define OB_DB_RELEASE_DPS 20.0f

void ob_drivebase_default_gains(ob_control_gains_t *g) {
    /*
     * Feed-forward from the ST-3032 torque-speed line (888 deg/s no-load at
     * 100 %, ~33 ms mechanical time constant with half of a 1 kg robot on a
     * 56 mm wheel, ~1 % Coulomb friction). The PD pair places the tracking
     * poles near 40 rad/s with a damping ratio of about 0.8; the integrator
     * removes what the model misses (a weak wheel, a slope, a heavier robot).
     */
    g->kp_pct_per_deg = 6.0f;
    g->ki_pct_per_deg_s = 30.0f;
    g->kd_pct_per_dps = 0.12f;
    g->ff_pct_per_dps = 100.0f / 888.0f;
    g->ff_pct_per_dps2 = 0.0037f;
    g->ff_static_pct = 1.0f;
    g->integral_band_deg = 5.0f;
    g->integral_limit_pct = 40.0f;
}

static bool positive_finite(float x) {
    return isfinite(x) && x > 0.0f;
}

static bool controller_active(const ob_drivebase_t *db) {
    return db->mode == OB_DB_MOVE || db->mode == OB_DB_SPEED || db->mode == OB_DB_STOPPING ||
           db->mode == OB_DB_HOLD;
}

static float elapsed_s(const ob_drivebase_t *db) {
    return (float)(uint32_t)(db->now_ms - db->start_ms) * 0.001f;
}

static float profile_duration_s(const ob_drivebase_t *db) {
    float ts = ob_trajectory_duration_s(&db->sum.trajectory);
    float td = ob_trajectory_duration_s(&db->diff.trajectory);
    return ts > td ? ts : td;
}

static void set_output(ob_drivebase_t *db, bool coast, float duty_left, float duty_right) {
    db->output.coast[OB_DB_LEFT] = coast;
    db->output.coast[OB_DB_RIGHT] = coast;
    db->output.duty_pct[OB_DB_LEFT] = coast ? 0.0f : duty_left;
    db->output.duty_pct[OB_DB_RIGHT] = coast ? 0.0f : duty_right;
}

/* Hand wheel i its output through io (only a change, unless forced: see ob_output_t). */
static void write_wheel(ob_drivebase_t *db, int i, bool force) {
    ob_output_write(&db->written[i], &db->io[i], db->output.coast[i], db->output.duty_pct[i], force);
}

/* Release both wheels now, from a command: the next tick would be up to a period late. */
static void write_coast_now(ob_drivebase_t *db) {
    set_output(db, true, 0.0f, 0.0f);
    for (int i = 0; i < 2; i++) {
        write_wheel(db, i, true);
    }
}

bool ob_drivebase_init(ob_drivebase_t *db, const ob_motor_io_t *left, const ob_motor_io_t *right,
                       float wheel_diameter_mm, float axle_track_mm) {
    static const ob_drivebase_t zero;
    *db = zero;
    if (!positive_finite(wheel_diameter_mm) || !positive_finite(axle_track_mm)) {
        return false;
    }
    if (left != NULL) {
        db->io[OB_DB_LEFT] = *left;
    }
    if (right != NULL) {
        db->io[OB_DB_RIGHT] = *right;
    }
    db->wheel_diameter_mm = wheel_diameter_mm;
    db->axle_track_mm = axle_track_mm;
    db->deg_per_mm = 360.0f / (OB_DB_PI * wheel_diameter_mm);
    db->diff_per_heading = axle_track_mm / wheel_diameter_mm;
    db->straight_speed_dps = OB_DB_DEFAULT_STRAIGHT_SPEED_DPS;
    db->turn_rate_dps = OB_DB_DEFAULT_TURN_RATE_DPS;
    db->acceleration_dps2 = OB_DB_DEFAULT_ACCELERATION_DPS2;
    db->turn_acceleration_dps2 = OB_DB_DEFAULT_TURN_ACCELERATION_DPS2;
    db->tolerances.position_deg = 0.3f;
    db->tolerances.speed_dps = 10.0f;
    db->tolerances.landing_deg = 2.0f;
    db->tolerances.pause_lag_deg = 5.0f;
    db->watchdog_ms = OB_DB_DEFAULT_WATCHDOG_MS;
    for (int i = 0; i < 2; i++) {
        ob_observer_init(&db->observer[i], OB_OBSERVER_DEFAULT_ALPHA, OB_OBSERVER_DEFAULT_BETA);
    }
    ob_drivebase_default_gains(&db->sum.gains);
    ob_drivebase_default_gains(&db->diff.gains);
    ob_integrator_set_limit(&db->sum.integrator, &db->sum.gains, OB_DB_MAX_DUTY);
    ob_integrator_set_limit(&db->diff.integrator, &db->diff.gains, OB_DB_MAX_DUTY);
    ob_trajectory_plan_hold(&db->sum.trajectory, 0.0f);
    ob_trajectory_plan_hold(&db->diff.trajectory, 0.0f);
    db->mode = OB_DB_IDLE;
    db->then = OB_THEN_COAST;
    db->done = true;
    set_output(db, true, 0.0f, 0.0f);
    return true;
}

bool ob_drivebase_settings(ob_drivebase_t *db, float straight_speed_dps, float turn_rate_dps,
                           float acceleration_dps2, float turn_acceleration_dps2) {
    if (!positive_finite(straight_speed_dps) || !positive_finite(turn_rate_dps) ||
        !positive_finite(acceleration_dps2) || !positive_finite(turn_acceleration_dps2)) {
        return false;
    }
    db->straight_speed_dps = straight_speed_dps;
    db->turn_rate_dps = turn_rate_dps;
    db->acceleration_dps2 = acceleration_dps2;
    db->turn_acceleration_dps2 = turn_acceleration_dps2;
    return true;
}

void ob_drivebase_set_gains(ob_drivebase_t *db, bool heading_axis, const ob_control_gains_t *gains) {
    ob_drivebase_axis_t *axis = heading_axis ? &db->diff : &db->sum;
    axis->gains = *gains;
    ob_integrator_set_limit(&axis->integrator, gains, OB_DB_MAX_DUTY);
}

/*
 * Where a new command starts each axis: on the current reference while the
 * controller runs (position and speed continuous, integrators kept, so
 * chained moves flow), on the measured state otherwise (integrators cleared:
 * they belong to the last controlled motion).
 */
static void begin_command(ob_drivebase_t *db, float *s0, float *vs0, float *d0, float *vd0) {
    if (controller_active(db)) {
        ob_trajectory_sample_t ss, sd;
        float t = elapsed_s(db);
        ob_trajectory_sample(&db->sum.trajectory, t, &ss);
        ob_trajectory_sample(&db->diff.trajectory, t, &sd);
        *s0 = ss.x_deg;
        *vs0 = ss.v_dps;
        *d0 = sd.x_deg;
        *vd0 = sd.v_dps;
    } else {
        *s0 = db->sum_deg;
        *vs0 = db->sum_dps;
        *d0 = db->diff_deg;
        *vd0 = db->diff_dps;
        ob_integrator_reset(&db->sum.integrator);
        ob_integrator_reset(&db->diff.integrator);
    }
    db->fault = 0;
    db->start_ms = db->now_ms;
    db->done = false;
    db->settling = false;
    db->landings = 0;
    db->pinned_ms = 0;
    db->plan_unconfirmed = true;
    db->plan_sum_deg = *s0;
    db->plan_diff_deg = *d0;
}

static void set_limits(ob_drivebase_axis_t *axis, float speed_dps, float accel_dps2) {
    axis->speed_dps = speed_dps;
    axis->accel_dps2 = accel_dps2;
}

/*
 * The axis a move does not drive: held where it is, or, if it is still
 * moving (chained after a curve or a drive), brought back to where it was
 * when the command came, so a straight after an arc keeps the arc's final
 * heading.
 */
static void plan_passive_axis(ob_drivebase_axis_t *axis, float x0, float v0, float speed_dps, float accel_dps2) {
    set_limits(axis, speed_dps, accel_dps2);
    axis->target_deg = x0;
    if (fabsf(v0) < OB_DB_REST_DPS) {
        ob_trajectory_plan_hold(&axis->trajectory, x0);
    } else {
        ob_trajectory_plan_move(&axis->trajectory, x0, v0, x0, speed_dps, accel_dps2, accel_dps2, false);
    }
}

bool ob_drivebase_straight(ob_drivebase_t *db, float distance_mm, ob_then_t then) {
    float travel_deg = distance_mm * db->deg_per_mm;
    if (!isfinite(travel_deg)) {
        return false; /* not finite, or too far to express in float wheel-degrees */
    }
    float s0, vs0, d0, vd0;
    begin_command(db, &s0, &vs0, &d0, &vd0);
    db->sum.target_deg = s0 + travel_deg;
    set_limits(&db->sum, db->straight_speed_dps, db->acceleration_dps2);
    ob_trajectory_plan_move(&db->sum.trajectory, s0, vs0, db->sum.target_deg, db->straight_speed_dps,
                            db->acceleration_dps2, db->acceleration_dps2, then == OB_THEN_CONTINUE);
    plan_passive_axis(&db->diff, d0, vd0, db->turn_rate_dps, db->turn_acceleration_dps2);
    db->mode = OB_DB_MOVE;
    db->then = then;
    return true;
}

bool ob_drivebase_turn(ob_drivebase_t *db, float angle_deg, ob_then_t then) {
    float turn_deg = angle_deg * db->diff_per_heading;
    if (!isfinite(turn_deg)) {
        return false;
    }
    float s0, vs0, d0, vd0;
    begin_command(db, &s0, &vs0, &d0, &vd0);
    db->diff.target_deg = d0 + turn_deg;
    set_limits(&db->diff, db->turn_rate_dps, db->turn_acceleration_dps2);
    ob_trajectory_plan_move(&db->diff.trajectory, d0, vd0, db->diff.target_deg, db->turn_rate_dps,
                            db->turn_acceleration_dps2, db->turn_acceleration_dps2, false);
    plan_passive_axis(&db->sum, s0, vs0, db->straight_speed_dps, db->acceleration_dps2);
    db->mode = OB_DB_MOVE;
    db->then = then == OB_THEN_CONTINUE ? OB_THEN_HOLD : then;
    return true;
}

bool ob_drivebase_curve(ob_drivebase_t *db, float radius_mm, float angle_deg, ob_then_t then) {
    if (!isfinite(radius_mm) || !isfinite(angle_deg)) {
        return false;
    }
    if (radius_mm == 0.0f) {
        return ob_drivebase_turn(db, angle_deg, then);
    }
    float radius_abs = fabsf(radius_mm);
    float distance_mm = ob_signf(radius_mm) * radius_abs * fabsf(angle_deg) * (OB_DB_PI / 180.0f);
    float sum_deg = distance_mm * db->deg_per_mm;
    float diff_deg = angle_deg * db->diff_per_heading;
    if (!isfinite(sum_deg) || !isfinite(diff_deg)) {
        return false;
    }
    float s0, vs0, d0, vd0;
    begin_command(db, &s0, &vs0, &d0, &vd0);
    /* The outer wheel runs at centre * (1 + track / 2|R|): scale so it meets the settings exactly. */
    float scale = radius_abs / (radius_abs + 0.5f * db->axle_track_mm);
    db->sum.target_deg = s0 + sum_deg;
    set_limits(&db->sum, db->straight_speed_dps * scale, db->acceleration_dps2 * scale);
    ob_trajectory_plan_move(&db->sum.trajectory, s0, vs0, db->sum.target_deg, db->sum.speed_dps,
                            db->sum.accel_dps2, db->sum.accel_dps2, then == OB_THEN_CONTINUE);
    if (sum_deg == 0.0f) {
        plan_passive_axis(&db->diff, d0, vd0, db->turn_rate_dps, db->turn_acceleration_dps2);
    } else {
        /* Heading proportional to distance at every instant: a true circle through the ramps. */
        float k = diff_deg / sum_deg;
        ob_trajectory_scaled(&db->sum.trajectory, k, d0, &db->diff.trajectory);
        db->diff.target_deg = d0 + diff_deg;
        set_limits(&db->diff, db->sum.speed_dps * fabsf(k), db->sum.accel_dps2 * fabsf(k));
    }
    db->mode = OB_DB_MOVE;
    db->then = then;
    return true;
}

/*
 * Ramp both axes to new speeds so that neither wheel changes speed faster
 * than accel_dps2 and both arrive together.
 */
static void plan_speed_ramps(ob_drivebase_t *db, float s0, float vs0, float d0, float vd0, float vs1, float vd1,
                             float accel_dps2) {
    float dvs = vs1 - vs0;
    float dvd = vd1 - vd0;
    float dv_wheel = fmaxf(fabsf(dvs + dvd), fabsf(dvs - dvd));
    float ramp_s = dv_wheel / accel_dps2;
    float as = ramp_s > 0.0f && fabsf(dvs) > 0.0f ? fabsf(dvs) / ramp_s : accel_dps2;
    float ad = ramp_s > 0.0f && fabsf(dvd) > 0.0f ? fabsf(dvd) / ramp_s : accel_dps2;
    ob_trajectory_plan_speed(&db->sum.trajectory, s0, vs0, vs1, as);
    ob_trajectory_plan_speed(&db->diff.trajectory, d0, vd0, vd1, ad);
    set_limits(&db->sum, vs1, as);
    set_limits(&db->diff, vd1, ad);
}

static bool command_speeds(ob_drivebase_t *db, float vs1, float vd1) {
    if (!isfinite(vs1) || !isfinite(vd1)) {
        return false;
    }
    float s0, vs0, d0, vd0;
    begin_command(db, &s0, &vs0, &d0, &vd0);
    plan_speed_ramps(db, s0, vs0, d0, vd0, vs1, vd1, db->acceleration_dps2);
    db->mode = OB_DB_SPEED;
    db->then = OB_THEN_CONTINUE;
    return true;
}

bool ob_drivebase_drive(ob_drivebase_t *db, float speed_mm_s, float turn_rate_dps) {
    return command_speeds(db, speed_mm_s * db->deg_per_mm, turn_rate_dps * db->diff_per_heading);
}

bool ob_drivebase_move_wheels(ob_drivebase_t *db, float left_dps, float right_dps) {
    return command_speeds(db, 0.5f * (left_dps + right_dps), 0.5f * (left_dps - right_dps));
}

/* Hold both axes where the robot is now (measured), keeping the integrators. */
static void hold_here(ob_drivebase_t *db) {
    set_limits(&db->sum, db->straight_speed_dps, db->acceleration_dps2);
    set_limits(&db->diff, db->turn_rate_dps, db->turn_acceleration_dps2);
    ob_trajectory_plan_hold(&db->sum.trajectory, db->sum_deg);
    ob_trajectory_plan_hold(&db->diff.trajectory, db->diff_deg);
    db->sum.target_deg = db->sum_deg;
    db->diff.target_deg = db->diff_deg;
    db->start_ms = db->now_ms;
    db->mode = OB_DB_HOLD;
}

void ob_drivebase_stop(ob_drivebase_t *db, ob_then_t then) {
    if (then == OB_THEN_COAST) {
        db->mode = OB_DB_IDLE;
        db->done = true;
        write_coast_now(db);
        return;
    }
    float s0, vs0, d0, vd0;
    begin_command(db, &s0, &vs0, &d0, &vd0);
    db->then = then == OB_THEN_BRAKE ? OB_THEN_BRAKE : OB_THEN_HOLD;
    if (fabsf(vs0) + fabsf(vd0) < OB_DB_REST_DPS) {
        /* Already at rest: nothing to decelerate. */
        if (db->then == OB_THEN_BRAKE) {
            db->mode = OB_DB_BRAKED;
            set_output(db, false, 0.0f, 0.0f);
        } else {
            hold_here(db);
        }
        db->done = true;
        return;
    }
    plan_speed_ramps(db, s0, vs0, d0, vd0, 0.0f, 0.0f, db->acceleration_dps2);
    db->sum.target_deg = ob_trajectory_end_deg(&db->sum.trajectory);
    db->diff.target_deg = ob_trajectory_end_deg(&db->diff.trajectory);
    db->mode = OB_DB_STOPPING;
}

/* The same trajectory, moved by -delta_deg: used when the frame under it moves by delta_deg. */
static void shift_axis(ob_drivebase_axis_t *axis, float delta_deg) {
    ob_trajectory_t shifted;
    ob_trajectory_sample_t start;
    ob_trajectory_sample(&axis->trajectory, 0.0f, &start);
    ob_trajectory_scaled(&axis->trajectory, 1.0f, start.x_deg - delta_deg, &shifted);
    axis->trajectory = shifted;
    axis->target_deg -= delta_deg;
}

/* Raw encoder coordinates from the observers, before any frame. */
static float encoder_sum_raw(const ob_drivebase_t *db) {
    return 0.5f * (db->observer[OB_DB_LEFT].x_deg + db->observer[OB_DB_RIGHT].x_deg);
}

static float encoder_diff_raw(const ob_drivebase_t *db) {
    return 0.5f * (db->observer[OB_DB_LEFT].x_deg - db->observer[OB_DB_RIGHT].x_deg);
}

bool ob_drivebase_reset(ob_drivebase_t *db) {
    if (!db->done) {
        return false;
    }
    /*
     * Shift every frame by the pose of the last step, all at the same
     * instant: the encoders', the gyro's (also while it is still bridging a
     * missed sample or waiting to be anchored), and the references held in
     * them, so a held position does not jump.
     */
    float ds = db->sum_deg;
    float dd = db->diff_deg;
    float enc_dd = encoder_diff_raw(db) - db->diff_zero_deg;
    db->sum_zero_deg += ds;
    db->diff_zero_deg += enc_dd;
    if (db->use_gyro) {
        db->heading_zero_deg += dd / db->diff_per_heading;
        db->gyro_diff_deg -= dd;
        db->gyro_enc_diff_deg -= enc_dd;
    }
    shift_axis(&db->sum, ds);
    shift_axis(&db->diff, dd);
    db->sum_deg = 0.0f;
    db->diff_deg = 0.0f;
    return true;
}

void ob_drivebase_use_gyro(ob_drivebase_t *db, const ob_heading_source_t *source) {
    if (source != NULL) {
        db->heading_source = *source;
        if (!db->use_gyro) {
            /* Continue from the encoder heading until the first gyro reading anchors the frame. */
            db->use_gyro = true;
            db->heading_aligned = false;
            db->gyro_diff_deg = db->diff_deg;
            db->gyro_enc_diff_deg = encoder_diff_raw(db) - db->diff_zero_deg;
            db->heading_last_ms = db->now_ms;
        }
    } else if (db->use_gyro) {
        /* Back to encoders: move their frame so the heading carries on from the gyro's. */
        db->use_gyro = false;
        db->diff_zero_deg = encoder_diff_raw(db) - db->diff_deg;
    }
}

bool ob_drivebase_done(const ob_drivebase_t *db) {
    return db->done;
}

uint8_t ob_drivebase_fault(const ob_drivebase_t *db) {
    return db->fault;
}

void ob_drivebase_get_state(const ob_drivebase_t *db, ob_drivebase_state_t *state) {
    state->distance_mm = db->sum_deg / db->deg_per_mm;
    state->drive_speed_mm_s = db->sum_dps / db->deg_per_mm;
    state->angle_deg = db->diff_deg / db->diff_per_heading;
    state->turn_rate_dps = db->diff_dps / db->diff_per_heading;
}

/* Update the observers and the measured (sum, diff); returns true when every feedback in use was fresh. */
static bool estimate(ob_drivebase_t *db, const ob_drivebase_feedback_t *fb, uint32_t dt_ms) {
    ob_period_update(&db->period, dt_ms);
    float dt_s = db->period.dt_s;
    bool fresh = true;
    for (int i = 0; i < 2; i++) {
        if (fb->wheel_ok[i] && isfinite(fb->wheel_deg[i])) {
            if (!db->wheel_seen[i]) {
                ob_observer_reset(&db->observer[i], fb->wheel_deg[i]);
                db->wheel_seen[i] = true;
                /* Distance and heading start at zero where the wheel stands at its first reading,
                 * not at the encoder's own zero: the motors may have turned before the drive base
                 * was built, and a first move armed before this reading planned from zero. */
                float half = 0.5f * fb->wheel_deg[i];
                db->sum_zero_deg += half;
                db->diff_zero_deg += i == OB_DB_LEFT ? half : -half;
            } else if (dt_ms > db->watchdog_ms) {
                /* The caller stalled (a long GC pause): the wheels went on meanwhile. */
                ob_observer_resync(&db->observer[i], fb->wheel_deg[i], dt_s);
            } else if (dt_ms > 0) {
                ob_observer_update_inv(&db->observer[i], fb->wheel_deg[i], dt_s, db->period.inv_dt);
            }
            db->wheel_last_ms[i] = db->now_ms;
        } else {
            fresh = false;
            if (db->wheel_seen[i] && dt_ms > 0) {
                ob_observer_predict(&db->observer[i], dt_s);
            }
        }
    }
    const ob_observer_t *l = &db->observer[OB_DB_LEFT];
    const ob_observer_t *r = &db->observer[OB_DB_RIGHT];
    float enc_diff = encoder_diff_raw(db) - db->diff_zero_deg;
    db->sum_deg = encoder_sum_raw(db) - db->sum_zero_deg;
    db->sum_dps = 0.5f * (l->v_dps + r->v_dps);
    db->diff_dps = 0.5f * (l->v_dps - r->v_dps);
    if (!db->use_gyro) {
        db->diff_deg = enc_diff;
        return fresh;
    }
    if (fb->heading_ok && isfinite(fb->heading_deg)) {
        if (!db->heading_aligned) {
            float bridged = db->gyro_diff_deg + (enc_diff - db->gyro_enc_diff_deg);
            db->heading_zero_deg = fb->heading_deg - bridged / db->diff_per_heading;
            db->heading_aligned = true;
        }
        db->diff_deg = (fb->heading_deg - db->heading_zero_deg) * db->diff_per_heading;
        db->gyro_diff_deg = db->diff_deg;
        db->gyro_enc_diff_deg = enc_diff;
        db->heading_last_ms = db->now_ms;
    } else {
        /* A missed gyro sample: bridge it with the encoders' rotation since the last one. */
        db->diff_deg = db->gyro_diff_deg + (enc_diff - db->gyro_enc_diff_deg);
        fresh = false;
    }
    return fresh;
}

/* control.h's plan confirmation: a command given while the drive base was not
 * being ticked is carried over to where the robot is now. */
static void confirm_plan(ob_drivebase_t *db) {
    if (!ob_control_plan_stale(&db->plan_unconfirmed, db->now_ms, db->start_ms, db->watchdog_ms)) {
        return;
    }
    shift_axis(&db->sum, db->plan_sum_deg - db->sum_deg);
    shift_axis(&db->diff, db->plan_diff_deg - db->diff_deg);
    db->start_ms = db->now_ms;
    /* The observers' speeds over the gap are averages that may include someone else's move. */
    db->sum_dps = db->sum.trajectory.v_dps[0];
    db->diff_dps = db->diff.trajectory.v_dps[0];
    db->observer[OB_DB_LEFT].v_dps = db->sum_dps + db->diff_dps;
    db->observer[OB_DB_RIGHT].v_dps = db->sum_dps - db->diff_dps;
}

/* OB_DB_FAULT_* bits of every feedback silent for longer than the watchdog allows. */
static uint8_t silent_feedback(const ob_drivebase_t *db) {
    uint8_t bits = 0;
    if ((uint32_t)(db->now_ms - db->wheel_last_ms[OB_DB_LEFT]) > db->watchdog_ms) {
        bits |= OB_DB_FAULT_LEFT;
    }
    if ((uint32_t)(db->now_ms - db->wheel_last_ms[OB_DB_RIGHT]) > db->watchdog_ms) {
        bits |= OB_DB_FAULT_RIGHT;
    }
    if (db->use_gyro && (uint32_t)(db->now_ms - db->heading_last_ms) > db->watchdog_ms) {
        bits |= OB_DB_FAULT_GYRO;
    }
    return bits;
}

static bool within_tolerance(const ob_drivebase_t *db) {
    const ob_drivebase_tolerances_t *tol = &db->tolerances;
    return fabsf(db->sum.target_deg - db->sum_deg) <= tol->position_deg &&
           fabsf(db->diff.target_deg - db->diff_deg) <= tol->position_deg &&
           fabsf(db->sum_dps) <= tol->speed_dps && fabsf(db->diff_dps) <= tol->speed_dps;
}

static bool needs_landing(const ob_drivebase_t *db) {
    float limit = db->tolerances.landing_deg;
    return fabsf(db->sum.target_deg - db->sum_deg) > limit || fabsf(db->diff.target_deg - db->diff_deg) > limit;
}

/*
 * Landing: re-plan the rest of the current command from where the robot
 * really is (position and speed), under the command's own speed and
 * acceleration limits. It closes a residual left when a profile expired
 * (the robot was held back or pushed), and it takes over when a pinned robot
 * is released, so the robot never lunges at a reference that ran or waited
 * elsewhere: no feedback step, ever.
 */
static void plan_axis_landing(ob_drivebase_axis_t *axis, float x_deg, float v_dps, bool end_at_cruise) {
    ob_trajectory_plan_move(&axis->trajectory, x_deg, v_dps, axis->target_deg, axis->speed_dps, axis->accel_dps2,
                            axis->accel_dps2, end_at_cruise);
}

static void plan_landing(ob_drivebase_t *db) {
    switch (db->mode) {
    case OB_DB_SPEED:
        plan_speed_ramps(db, db->sum_deg, db->sum_dps, db->diff_deg, db->diff_dps, db->sum.speed_dps,
                         db->diff.speed_dps, db->acceleration_dps2);
        break;
    case OB_DB_STOPPING:
        plan_speed_ramps(db, db->sum_deg, db->sum_dps, db->diff_deg, db->diff_dps, 0.0f, 0.0f,
                         db->acceleration_dps2);
        break;
    default:
        /* Moves and hold: back onto the targets (a continue move keeps its cruise at the end). */
        plan_axis_landing(&db->sum, db->sum_deg, db->sum_dps, db->mode == OB_DB_MOVE && db->then == OB_THEN_CONTINUE);
        plan_axis_landing(&db->diff, db->diff_deg, db->diff_dps, false);
        break;
    }
    db->start_ms = db->now_ms;
    db->settling = false;
    db->pinned_ms = 0;
    db->landings++;
}

/* Apply a finished move's end state. Returns true when control stops here. */
static bool finish(ob_drivebase_t *db) {
    db->done = true;
    switch (db->then) {
    case OB_THEN_COAST:
        db->mode = OB_DB_IDLE;
        set_output(db, true, 0.0f, 0.0f);
        return true;
    case OB_THEN_BRAKE:
        db->mode = OB_DB_BRAKED;
        set_output(db, false, 0.0f, 0.0f);
        return true;
    default:
        db->mode = OB_DB_HOLD;
        return false;
    }
}

/* Advance the mode's state machine. Returns true when control stops this step. */
static bool supervise(ob_drivebase_t *db) {
    float t = elapsed_s(db);
    switch (db->mode) {
    case OB_DB_MOVE:
        if (db->then == OB_THEN_CONTINUE) {
            db->done = db->done || t >= profile_duration_s(db);
            return false;
        }
        if (!db->settling && t >= profile_duration_s(db)) {
            db->settling = true;
        }
        if (db->settling) {
            if (needs_landing(db)) {
                plan_landing(db);
            } else if (within_tolerance(db)) {
                return finish(db);
            }
        }
        return false;
    case OB_DB_SPEED:
        db->done = db->done || t >= profile_duration_s(db);
        return false;
    case OB_DB_STOPPING:
        if (t < profile_duration_s(db)) {
            return false;
        }
        if (db->then == OB_THEN_BRAKE) {
            return finish(db);
        }
        /* hold anchors where the robot actually came to rest, not where the ramp said it would. */
        hold_here(db);
        db->done = true;
        return false;
    default:
        return false;
    }
}

static void control(ob_drivebase_t *db, bool fresh, uint32_t dt_ms) {
    if (db->pinned_ms >= OB_DB_PINNED_MIN_MS && fabsf(db->sum_dps) + fabsf(db->diff_dps) > OB_DB_RELEASE_DPS) {
        plan_landing(db); /* released: carry on from here rather than lunge at the paused reference */
    }
    ob_trajectory_sample_t rs, rd;
    float t = elapsed_s(db);
    float dt_s = fminf(db->period.dt_s, OB_DB_MAX_DT_S);
    ob_trajectory_sample(&db->sum.trajectory, t, &rs);
    ob_trajectory_sample(&db->diff.trajectory, t, &rd);
    float es = rs.x_deg - db->sum_deg;
    float ed = rd.x_deg - db->diff_deg;
    float us = ob_control_duty(&db->sum.gains, &rs, es, db->sum_dps, &db->sum.integrator);
    float ud = ob_control_duty(&db->diff.gains, &rd, ed, db->diff_dps, &db->diff.integrator);
    /* The heading loop has first call on the duty range; forward progress gets what is left. */
    float ud_sat = ob_clampf(ud, OB_DB_MAX_DUTY);
    float room = OB_DB_MAX_DUTY - fabsf(ud_sat);
    float us_sat = ob_clampf(us, room);
    if (fresh && dt_s > 0.0f) {
        ob_integrator_update(&db->sum.integrator, &db->sum.gains, &rs, es, us - us_sat, dt_s);
        ob_integrator_update(&db->diff.integrator, &db->diff.gains, &rd, ed, ud - ud_sat, dt_s);
    }
    /*
     * A robot that cannot keep up (blocked, overloaded, a weak wheel at top
     * speed) pauses the clock of its trajectories, both axes together so a
     * curve stays a circle: the reference waits instead of running away, and
     * nothing has to be caught up at full duty when the robot is released.
     */
    float lag = db->tolerances.pause_lag_deg;
    bool pinned = ((us - us_sat) * es > 0.0f && fabsf(es) > lag) || ((ud - ud_sat) * ed > 0.0f && fabsf(ed) > lag);
    if (pinned) {
        db->start_ms += dt_ms;
        db->pinned_ms += dt_ms;
    } else if (db->pinned_ms >= OB_DB_PINNED_MIN_MS) {
        plan_landing(db);
    } else {
        db->pinned_ms = 0;
    }
    set_output(db, false, us_sat + ud_sat, us_sat - ud_sat);
}

void ob_drivebase_step(ob_drivebase_t *db, uint32_t now_ms, const ob_drivebase_feedback_t *feedback,
                       ob_drivebase_output_t *output) {
    uint32_t dt_ms = 0;
    if (!db->clock_started) {
        db->clock_started = true;
        db->wheel_last_ms[OB_DB_LEFT] = now_ms;
        db->wheel_last_ms[OB_DB_RIGHT] = now_ms;
        db->heading_last_ms = now_ms;
        db->start_ms = now_ms;
    } else {
        dt_ms = now_ms - db->now_ms;
    }
    db->now_ms = now_ms;
    bool fresh = estimate(db, feedback, dt_ms);

    if (controller_active(db)) {
        uint8_t silent = silent_feedback(db);
        if (silent != 0) {
            /* Halt, do not chase: a frozen reading looks like an ever-growing error. */
            db->fault = silent;
            db->mode = OB_DB_FAULT;
            db->done = true;
            ob_integrator_reset(&db->sum.integrator);
            ob_integrator_reset(&db->diff.integrator);
            set_output(db, true, 0.0f, 0.0f);
        } else {
            confirm_plan(db);
            if (!supervise(db)) {
                control(db, fresh, dt_ms);
            }
        }
    } else if (db->mode == OB_DB_BRAKED) {
        set_output(db, false, 0.0f, 0.0f);
    } else {
        set_output(db, true, 0.0f, 0.0f);
    }
    if (output != NULL) {
        *output = db->output;
    }
}

void ob_drivebase_tick(void *ctx, uint32_t now_ms) {
    ob_drivebase_t *db = (ob_drivebase_t *)ctx;
    ob_drivebase_feedback_t fb;
    for (int i = 0; i < 2; i++) {
        fb.wheel_deg[i] = 0.0f;
        fb.wheel_ok[i] = db->io[i].read_angle != NULL && db->io[i].read_angle(db->io[i].ctx, &fb.wheel_deg[i]);
    }
    fb.heading_deg = 0.0f;
    fb.heading_ok = db->use_gyro && db->heading_source.read_heading != NULL &&
                    db->heading_source.read_heading(db->heading_source.ctx, &fb.heading_deg);
    ob_drivebase_step(db, now_ms, &fb, NULL);
    for (int i = 0; i < 2; i++) {
        write_wheel(db, i, false);
    }
}
