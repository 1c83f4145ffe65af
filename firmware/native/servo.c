/*
 * Closed-loop motor control: see servo.h for the control law.
 *
 * Time is the scheduler's measured clock. A command starts its trajectory at
 * the time of the last tick, and every tick samples the trajectory at the
 * time it is given, so ticks that arrive late or not at all cost control
 * updates but never slow the move down.
 */
#include "servo.h"

#include <math.h>
#include <stddef.h>

/* Speed runs re-base their trajectory after this long, so the time and
 * position arithmetic stays in the range where float keeps its resolution. */
#define OB_SERVO_REBASE_S 60.0f

void ob_servo_config_default(ob_servo_config_t *cfg) {
    /* The plant: about 270 deg/s^2 per percent of duty and a back-EMF
     * damping of 30 /s. These gains place the position loop near 50 rad/s,
     * critically damped; the speed loop mirrors it, with the position error
     * as the speed integral. */
    cfg->kp_pct_per_deg = 9.0f;
    cfg->ki_pct_per_deg_s = 100.0f;
    cfg->kd_pct_per_dps = 0.25f;
    cfg->integral_band_deg = 5.0f;
    cfg->integral_limit_pct = 30.0f;
    cfg->speed_kp_pct_per_dps = 0.25f;
    cfg->speed_ki_pct_per_deg = 9.0f;
    cfg->ff_pct_per_dps = 100.0f / 888.0f;
    cfg->ff_pct_per_dps2 = 0.0037f;
    cfg->ff_static_pct = 1.0f;
    cfg->max_speed_dps = 850.0f;
    cfg->accel_dps2 = 1500.0f;
    cfg->decel_dps2 = 1500.0f;
    cfg->duty_limit_pct = 100.0f;
    cfg->position_tolerance_deg = 1.0f;
    cfg->speed_tolerance_dps = 30.0f;
    cfg->stall_error_deg = 10.0f;
    cfg->stall_speed_dps = 20.0f;
    cfg->stall_time_ms = 200u;
    cfg->silent_timeout_ms = 20u;
    cfg->counts_per_rev = 4096.0f;
    cfg->observer_alpha = OB_OBSERVER_DEFAULT_ALPHA;
    cfg->observer_beta = OB_OBSERVER_DEFAULT_BETA;
}

static bool direct_read_angle(void *ctx, float *angle_deg) {
    (void)ctx;
    (void)angle_deg;
    return false;
}

static void direct_write_duty(void *ctx, float duty_pct) {
    (void)ctx;
    (void)duty_pct;
}

static void direct_write_coast(void *ctx) {
    (void)ctx;
}

const ob_motor_io_t ob_servo_direct_io = {direct_read_angle, direct_write_duty, direct_write_coast, NULL};

/* ---- Output: only what changed reaches the hardware. ---- */

static void output_coast(ob_servo_t *s) {
    ob_output_write(&s->output, &s->io, true, 0.0f, false);
}

static void output_duty(ob_servo_t *s, float duty_pct) {
    ob_output_write(&s->output, &s->io, false, duty_pct, false);
}

/* ---- State shared by the commands. ---- */

static void apply_config(ob_servo_t *s, const ob_servo_config_t *cfg) {
    s->cfg = *cfg;
    float counts = cfg->counts_per_rev > 0.0f ? cfg->counts_per_rev : 4096.0f;
    s->integrator.deadband_deg = 0.5f * 360.0f / counts;
    s->position_gains = (ob_control_gains_t){
        .kp_pct_per_deg = cfg->kp_pct_per_deg,
        .ki_pct_per_deg_s = cfg->ki_pct_per_deg_s,
        .kd_pct_per_dps = cfg->kd_pct_per_dps,
        .ff_pct_per_dps = cfg->ff_pct_per_dps,
        .ff_pct_per_dps2 = cfg->ff_pct_per_dps2,
        .ff_static_pct = cfg->ff_static_pct,
        .integral_band_deg = cfg->integral_band_deg,
        .integral_limit_pct = cfg->integral_limit_pct,
    };
    s->speed_gains = s->position_gains;
    s->speed_gains.kp_pct_per_deg = cfg->speed_ki_pct_per_deg;
    s->speed_gains.ki_pct_per_deg_s = 0.0f;
    s->speed_gains.kd_pct_per_dps = cfg->speed_kp_pct_per_dps;
    s->observer.alpha = cfg->observer_alpha > 0.0f && cfg->observer_alpha <= 1.0f
                            ? cfg->observer_alpha
                            : OB_OBSERVER_DEFAULT_ALPHA;
    s->observer.beta = cfg->observer_beta > 0.0f && cfg->observer_beta <= 1.0f ? cfg->observer_beta
                                                                               : OB_OBSERVER_DEFAULT_BETA;
}

/* Recompute the limits that would otherwise cost a division every tick. */
static void refresh_limits(ob_servo_t *s) {
    float ki_speed = s->cfg.speed_ki_pct_per_deg;
    s->speed_error_max_deg = ki_speed > 0.0f ? s->duty_limit_pct / ki_speed : 0.0f;
    ob_integrator_set_limit(&s->integrator, &s->position_gains, s->duty_limit_pct);
}

void ob_servo_init(ob_servo_t *s, const ob_motor_io_t *io, const ob_servo_config_t *cfg) {
    *s = (ob_servo_t){0};
    s->io = *io;
    ob_observer_init(&s->observer, cfg->observer_alpha, cfg->observer_beta);
    apply_config(s, cfg);
    s->duty_limit_pct = ob_clampf(cfg->duty_limit_pct, 100.0f);
    if (s->duty_limit_pct < 0.0f) {
        s->duty_limit_pct = 0.0f;
    }
    refresh_limits(s);
    s->mode = OB_SERVO_COAST;
    s->output.coasting = true;
    s->done = true;
    ob_trajectory_plan_hold(&s->trajectory, 0.0f);
}

void ob_servo_configure(ob_servo_t *s, const ob_servo_config_t *cfg) {
    apply_config(s, cfg);
    refresh_limits(s);
}

void ob_servo_set_duty_limit(ob_servo_t *s, float limit_pct) {
    s->duty_limit_pct = limit_pct > 100.0f ? 100.0f : (limit_pct > 0.0f ? limit_pct : 0.0f);
    refresh_limits(s);
}

static bool closed_loop(const ob_servo_t *s) {
    return s->mode == OB_SERVO_SPEED || s->mode == OB_SERVO_POSITION;
}

/* Whether a new command may start from the running reference: only while
 * the motor is really following it (not stalled, not far behind). Asked
 * before the new command resets the status. */
static bool following_reference(const ob_servo_t *s) {
    float error = s->ref.x_deg + s->ref_offset_deg - s->angle_deg;
    return closed_loop(s) && !s->needs_plan && !s->stalled && fabsf(error) < s->cfg.stall_error_deg;
}

/* Every new command forgets the previous one's integrator and status. */
static void begin_command(ob_servo_t *s, ob_servo_mode_t mode) {
    s->mode = mode;
    ob_integrator_reset(&s->integrator);
    s->ref_offset_deg = 0.0f;
    s->stalled = false;
    s->stall_timing = false;
    s->feedback_lost = false;
    s->done = mode != OB_SERVO_SPEED && mode != OB_SERVO_POSITION;
}

/* Where a new trajectory starts: the running reference when one is being
 * tracked (so chained commands join without a bump, and repeated run_angle
 * calls do not accumulate tracking errors), the measurement otherwise. */
static void start_state(const ob_servo_t *s, bool was_tracking, float *x_deg, float *v_dps) {
    if (was_tracking) {
        *x_deg = s->ref.x_deg + s->ref_offset_deg;
        *v_dps = s->ref.v_dps;
    } else {
        *x_deg = s->angle_deg;
        *v_dps = s->observer.v_dps;
    }
}

static float capped_speed(const ob_servo_t *s, float speed_dps) {
    return ob_clampf(speed_dps, s->cfg.max_speed_dps);
}

static void plan_from(ob_servo_t *s, float x0, float v0) {
    s->start_ms = s->now_ms;
    s->needs_plan = false;
    if (s->mode == OB_SERVO_SPEED) {
        ob_trajectory_plan_speed(&s->trajectory, x0, v0, s->cmd_speed_dps, s->cmd_accel_dps2);
    } else {
        float target = s->cmd_value_deg;
        if (s->cmd_relative) {
            float direction = ob_signf(s->cmd_speed_dps) * ob_signf(s->cmd_value_deg);
            target = x0 + direction * fabsf(s->cmd_value_deg);
        }
        float speed = fabsf(s->cmd_speed_dps);
        if (speed > 0.0f) {
            ob_trajectory_plan_move(&s->trajectory, x0, v0, target, speed, s->cmd_accel_dps2,
                                    s->cmd_decel_dps2, s->then == OB_THEN_CONTINUE);
        } else {
            ob_trajectory_plan_hold(&s->trajectory, x0);
        }
    }
    ob_trajectory_sample(&s->trajectory, 0.0f, &s->ref);
}

static void plan(ob_servo_t *s, bool was_tracking) {
    float x0;
    float v0;
    start_state(s, was_tracking, &x0, &v0);
    plan_from(s, x0, v0);
}

/* Plan now if the state is known, else as soon as the first reading arrives. */
static void plan_or_defer(ob_servo_t *s, bool was_tracking) {
    if (s->have_angle) {
        plan(s, was_tracking);
        s->plan_unconfirmed = true;
    } else {
        s->needs_plan = true;
    }
}

/* control.h's plan confirmation: a command given while the servo was not
 * being ticked is planned again from the first fresh reading. */
static void confirm_plan(ob_servo_t *s, uint32_t now_ms) {
    bool stale = ob_control_plan_stale(&s->plan_unconfirmed, now_ms, s->start_ms, s->cfg.silent_timeout_ms);
    if (stale && closed_loop(s)) {
        /* The observer's speed over the gap is an average that may include someone else's move. */
        float v0 = s->trajectory.v_dps[0];
        s->observer.v_dps = v0;
        plan_from(s, s->angle_deg, v0);
    }
}

/* ---- Commands. ---- */

void ob_servo_run_speed(ob_servo_t *s, float speed_dps) {
    bool was_tracking = following_reference(s);
    begin_command(s, OB_SERVO_SPEED);
    s->cmd_speed_dps = capped_speed(s, speed_dps);
    s->cmd_accel_dps2 = s->cfg.accel_dps2;
    plan_or_defer(s, was_tracking);
}

void ob_servo_move(ob_servo_t *s, float speed_dps, float value_deg, bool relative, ob_then_t then,
                   float accel_dps2, float decel_dps2) {
    bool was_tracking = following_reference(s);
    begin_command(s, OB_SERVO_POSITION);
    s->then = then;
    s->cmd_speed_dps = capped_speed(s, speed_dps);
    s->cmd_value_deg = value_deg;
    s->cmd_relative = relative;
    s->cmd_accel_dps2 = accel_dps2;
    s->cmd_decel_dps2 = decel_dps2;
    plan_or_defer(s, was_tracking);
}

void ob_servo_run_target(ob_servo_t *s, float speed_dps, float target_deg, ob_then_t then) {
    ob_servo_move(s, speed_dps, target_deg, false, then, s->cfg.accel_dps2, s->cfg.decel_dps2);
}

void ob_servo_run_angle(ob_servo_t *s, float speed_dps, float angle_deg, ob_then_t then) {
    ob_servo_move(s, speed_dps, angle_deg, true, then, s->cfg.accel_dps2, s->cfg.decel_dps2);
}

void ob_servo_hold(ob_servo_t *s) {
    begin_command(s, OB_SERVO_POSITION);
    s->then = OB_THEN_HOLD;
    s->cmd_speed_dps = 0.0f; /* a zero-speed move is a hold where it stands */
    s->cmd_value_deg = 0.0f;
    s->cmd_relative = true;
    plan_or_defer(s, false);
}

void ob_servo_dc(ob_servo_t *s, float duty_pct) {
    begin_command(s, OB_SERVO_DUTY);
    s->needs_plan = false;
    s->duty_cmd_pct = ob_clampf(duty_pct, 100.0f);
    output_duty(s, ob_clampf(s->duty_cmd_pct, s->duty_limit_pct));
}

void ob_servo_brake(ob_servo_t *s) {
    begin_command(s, OB_SERVO_BRAKE);
    s->needs_plan = false;
    output_duty(s, 0.0f);
}

void ob_servo_coast(ob_servo_t *s) {
    begin_command(s, OB_SERVO_COAST);
    s->needs_plan = false;
    output_coast(s);
}

void ob_servo_stop(ob_servo_t *s, ob_then_t then) {
    if (then == OB_THEN_HOLD) {
        ob_servo_hold(s);
    } else if (then == OB_THEN_BRAKE) {
        ob_servo_brake(s);
    } else {
        ob_servo_coast(s);
    }
}

void ob_servo_reset_angle(ob_servo_t *s, float angle_deg) {
    if (!s->have_angle) {
        s->reset_pending = true;
        s->reset_to_deg = angle_deg;
        return;
    }
    float delta = angle_deg - s->angle_deg;
    s->offset_deg += delta;
    s->angle_deg = angle_deg;
    s->observer.x_deg += delta;
    s->ref.x_deg += delta;
    for (int i = 0; i < 4; i++) {
        s->trajectory.x_deg[i] += delta;
    }
    if (!s->cmd_relative) {
        s->cmd_value_deg += delta;
    }
}

/* ---- The control update. ---- */

/* Position at which a finished move is judged, and whether it is there. */
static bool on_target(const ob_servo_t *s) {
    float error = ob_trajectory_end_deg(&s->trajectory) - s->angle_deg;
    return fabsf(error) <= s->cfg.position_tolerance_deg &&
           fabsf(s->observer.v_dps) <= s->cfg.speed_tolerance_dps;
}

static void update_stall(ob_servo_t *s, float error_deg, float duty_unclamped, uint32_t now_ms) {
    bool pushing = fabsf(duty_unclamped) >= s->duty_limit_pct || fabsf(error_deg) >= s->cfg.stall_error_deg;
    bool slow = fabsf(s->observer.v_dps) < s->cfg.stall_speed_dps;
    if (pushing && slow) {
        if (!s->stall_timing) {
            s->stall_timing = true;
            s->stall_since_ms = now_ms;
        }
        s->stalled = now_ms - s->stall_since_ms >= s->cfg.stall_time_ms;
    } else {
        s->stall_timing = false;
        s->stalled = false;
    }
}

static float speed_control(ob_servo_t *s, float t_s) {
    if (t_s > OB_SERVO_REBASE_S && t_s > ob_trajectory_duration_s(&s->trajectory)) {
        ob_trajectory_plan_speed(&s->trajectory, s->ref.x_deg + s->ref_offset_deg, s->ref.v_dps,
                                 s->ref.v_dps, s->cmd_accel_dps2);
        s->ref_offset_deg = 0.0f;
        s->start_ms = s->now_ms;
        ob_trajectory_sample(&s->trajectory, 0.0f, &s->ref);
    }
    float error = s->ref.x_deg + s->ref_offset_deg - s->angle_deg;
    /* Drag the reference so the speed integral alone never exceeds the duty
     * limit: a blocked motor pushes at the limit without winding up. */
    float ki = s->cfg.speed_ki_pct_per_deg;
    if (ki > 0.0f) {
        float error_max = s->speed_error_max_deg;
        if (error > error_max) {
            s->ref_offset_deg -= error - error_max;
            error = error_max;
        } else if (error < -error_max) {
            s->ref_offset_deg -= error + error_max;
            error = -error_max;
        }
    }
    float duty = ob_control_duty(&s->speed_gains, &s->ref, error, s->observer.v_dps, &s->integrator);
    update_stall(s, error, duty, s->now_ms);
    return duty;
}

static float position_control(ob_servo_t *s, float dt_s) {
    float error = s->ref.x_deg - s->angle_deg;
    const ob_control_gains_t *g = &s->position_gains;
    float before = s->integrator.integral_deg_s;
    float duty = ob_control_duty(g, &s->ref, error, s->observer.v_dps, &s->integrator);
    ob_integrator_update(&s->integrator, g, &s->ref, error, duty - ob_clampf(duty, s->duty_limit_pct), dt_s);
    duty += g->ki_pct_per_deg_s * (s->integrator.integral_deg_s - before);
    update_stall(s, error, duty, s->now_ms);
    return duty;
}

/* then= at the end of a position move. */
static void finish_move(ob_servo_t *s, float t_s) {
    if (s->done || t_s < ob_trajectory_duration_s(&s->trajectory)) {
        return;
    }
    if (s->then == OB_THEN_CONTINUE) {
        s->done = true; /* past the target at cruise: keep tracking the tail */
        return;
    }
    if (!on_target(s) && !s->stalled) {
        return;
    }
    s->done = true;
    if (s->then == OB_THEN_COAST) {
        s->mode = OB_SERVO_COAST;
        output_coast(s);
    } else if (s->then == OB_THEN_BRAKE) {
        s->mode = OB_SERVO_BRAKE;
        output_duty(s, 0.0f);
    }
}

static void read_feedback(ob_servo_t *s, uint32_t now_ms, uint32_t dt_ms, bool have_angle, float sensor_deg) {
    ob_period_update(&s->period, dt_ms);
    if (!have_angle) {
        s->failed_reads++;
        s->silent_ticks++;
        ob_observer_predict(&s->observer, s->period.dt_s);
        return;
    }
    s->silent_ticks = 0u;
    s->last_read_ms = now_ms;
    if (!s->have_angle) {
        s->have_angle = true;
        if (s->reset_pending) {
            s->offset_deg = s->reset_to_deg - sensor_deg;
            s->reset_pending = false;
        }
        s->angle_deg = sensor_deg + s->offset_deg;
        ob_observer_reset(&s->observer, s->angle_deg);
        return;
    }
    s->angle_deg = sensor_deg + s->offset_deg;
    if (dt_ms > s->cfg.silent_timeout_ms) {
        /* The caller stalled (a long GC pause): the motor went on meanwhile. */
        ob_observer_resync(&s->observer, s->angle_deg, s->period.dt_s);
    } else {
        ob_observer_update_inv(&s->observer, s->angle_deg, s->period.dt_s, s->period.inv_dt);
    }
}

void ob_servo_step(ob_servo_t *s, uint32_t now_ms, bool have_angle, float sensor_deg) {
    uint32_t dt_ms = s->clock_valid ? now_ms - s->now_ms : 0u;
    if (!s->clock_valid) {
        s->clock_valid = true;
        s->last_read_ms = now_ms;
    }
    s->now_ms = now_ms;
    read_feedback(s, now_ms, dt_ms, have_angle, sensor_deg);

    if (!have_angle) {
        /* Stale feedback: keep the last output through a short gap (a dropped
         * packet), never integrate on it, and halt a closed loop once the
         * angle has been silent for too long. */
        bool silent_too_long = now_ms - s->last_read_ms >= s->cfg.silent_timeout_ms;
        if (silent_too_long && (closed_loop(s) || s->needs_plan)) {
            s->feedback_lost = true;
            s->mode = OB_SERVO_COAST;
            ob_integrator_reset(&s->integrator);
            s->needs_plan = false;
            s->done = true;
            output_coast(s);
        }
        return;
    }
    if (s->needs_plan) {
        s->start_ms = now_ms;
        plan(s, false);
    }
    confirm_plan(s, now_ms);

    float duty;
    switch (s->mode) {
    case OB_SERVO_SPEED:
    case OB_SERVO_POSITION: {
        float t_s = 0.001f * (float)(now_ms - s->start_ms);
        ob_trajectory_sample(&s->trajectory, t_s, &s->ref);
        if (s->mode == OB_SERVO_SPEED) {
            duty = speed_control(s, t_s);
        } else {
            duty = position_control(s, s->period.dt_s);
        }
        output_duty(s, ob_clampf(duty, s->duty_limit_pct));
        if (s->mode == OB_SERVO_POSITION) {
            finish_move(s, t_s);
        }
        break;
    }
    case OB_SERVO_DUTY:
        output_duty(s, ob_clampf(s->duty_cmd_pct, s->duty_limit_pct));
        break;
    case OB_SERVO_BRAKE:
        output_duty(s, 0.0f);
        break;
    case OB_SERVO_COAST:
    default:
        output_coast(s);
        break;
    }
}

void ob_servo_tick(void *servo, uint32_t now_ms) {
    ob_servo_t *s = (ob_servo_t *)servo;
    float sensor_deg = 0.0f;
    bool ok = s->io.read_angle(s->io.ctx, &sensor_deg);
    ob_servo_step(s, now_ms, ok, sensor_deg);
}
