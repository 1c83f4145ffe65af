/*
 * The feedback law every closed loop of the cores shares (pbio control.c and
 * integrator.c in spirit): the servo's position and speed loops and both axes
 * of the drivebase call these, so the rules below hold for all of them.
 *
 *   duty = ff + kp * (x_ref - x) + kd * (v_ref - v) + ki * I
 *   ff   = ff_speed * v_ref + ff_accel * a_ref + ff_static * sign(v_ref)
 *
 * Integrator rules (one set, for every loop):
 *   - integrate on fresh feedback only (callers do not call it otherwise);
 *   - while the reference is speeding up, cruising or at rest, not while it
 *     slows down (a * v < 0). Braking toward a target, the error is mostly
 *     the feed-forward's misfit of the braking (inertia, back-EMF), which
 *     reverses once the reference stops: integrated, it is carried into the
 *     hold as a push past the target, which static friction then freezes in
 *     (an MG370 stuck 0.1 deg past its target for 300 ms). A lasting load (a
 *     slope, a weak wheel, friction) shows in the other phases too and is
 *     integrated there, so a move ends with the integrator already charged
 *     with it; an integrator that waits for a steady reference meets the end
 *     of every turn with the load uncorrected, and a held drive base keeps
 *     creeping after the move is done (still 0.06 deg 100 ms later);
 *   - the error is clipped to integral_band_deg first, so one transient (a
 *     bump, a landing) charges the integrator at a bounded rate, while a
 *     large error that lasts (a heavy load) is still integrated rather than
 *     left to the proportional term alone;
 *   - not inside the dead band (half an encoder count, where the loop knows
 *     its encoder's resolution: the servo): quantisation noise would make a
 *     holding motor hunt;
 *   - never deeper into saturation: not while the output is clipped in the
 *     direction the error pushes (that is wind-up);
 *   - ki * I is bounded by integral_limit_pct and by the duty cap.
 *
 * Units follow the manual: degrees, deg/s, deg/s^2; duty in percent.
 */
#ifndef OB_CONTROL_H
#define OB_CONTROL_H

#include <math.h>
#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "ob_types.h"
#include "trajectory.h"

/* Gains of one loop, named with their units. */
typedef struct {
    float kp_pct_per_deg;     /* duty per degree of position error */
    float ki_pct_per_deg_s;   /* duty per degree-second of integrated error */
    float kd_pct_per_dps;     /* duty per deg/s of speed error */
    float ff_pct_per_dps;     /* duty per deg/s of reference speed (back-EMF, viscous friction) */
    float ff_pct_per_dps2;    /* duty per deg/s^2 of reference acceleration (inertia) */
    float ff_static_pct;      /* duty in the direction of the reference speed (Coulomb friction) */
    float integral_band_deg;  /* errors are clipped to this before they are integrated */
    float integral_limit_pct; /* bound on ki * I */
} ob_control_gains_t;

/* The integrated position error of one loop and its bounds. */
typedef struct {
    float integral_deg_s;
    float max_deg_s;          /* ki * max_deg_s is the integral's share of the duty at most */
    float deadband_deg;       /* errors this small are not integrated */
} ob_integrator_t;

/* What a motor was last told, so that only a change reaches it: on the hub
 * every write is a bus transfer or a Python call, and an idle controller must
 * not keep re-asserting itself on a motor someone else may be driving. */
typedef struct {
    bool valid;               /* something was written since init */
    bool coasting;            /* released */
    float duty_pct;           /* written last; 0 while coasting */
} ob_output_t;

/* The tick spacing and what is derived from it, recomputed only when it changes. */
typedef struct {
    uint32_t dt_ms;
    float dt_s;
    float inv_dt;             /* 1 / dt_s, 0 for a zero spacing */
} ob_period_t;

static inline float ob_clampf(float x, float limit) {
    return x > limit ? limit : (x < -limit ? -limit : x);
}

static inline float ob_signf(float x) {
    return x > 0.0f ? 1.0f : (x < 0.0f ? -1.0f : 0.0f);
}

/* Feed-forward from the reference alone. */
static inline float ob_control_feed_forward(const ob_control_gains_t *g, const ob_trajectory_sample_t *ref) {
    return g->ff_pct_per_dps * ref->v_dps + g->ff_pct_per_dps2 * ref->a_dps2 +
           g->ff_static_pct * ob_signf(ref->v_dps);
}

/* Duty before saturation, for a position error the caller measured (and may have limited). */
static inline float ob_control_duty(const ob_control_gains_t *g, const ob_trajectory_sample_t *ref, float error_deg,
                                    float v_dps, const ob_integrator_t *itg) {
    return ob_control_feed_forward(g, ref) + g->kp_pct_per_deg * error_deg + g->kd_pct_per_dps * (ref->v_dps - v_dps) +
           g->ki_pct_per_deg_s * itg->integral_deg_s;
}

/* Recompute the integrator's bound after the gains or the duty cap changed. */
void ob_integrator_set_limit(ob_integrator_t *itg, const ob_control_gains_t *g, float duty_limit_pct);

/*
 * One integration step under the rules above, at reference ref. excess_pct is
 * how far the duty asked for lies beyond what is applied (duty - clamp(duty)),
 * the sign included.
 */
static inline void ob_integrator_update(ob_integrator_t *itg, const ob_control_gains_t *g,
                                        const ob_trajectory_sample_t *ref, float error_deg, float excess_pct,
                                        float dt_s) {
    if (g->ki_pct_per_deg_s <= 0.0f) {
        return;
    }
    bool slowing_down = ref->a_dps2 * ref->v_dps < 0.0f;
    bool winding_up = excess_pct * error_deg > 0.0f;
    if (!slowing_down && !winding_up && fabsf(error_deg) > itg->deadband_deg) {
        itg->integral_deg_s += ob_clampf(error_deg, g->integral_band_deg) * dt_s;
    }
    itg->integral_deg_s = ob_clampf(itg->integral_deg_s, itg->max_deg_s);
}

static inline void ob_integrator_reset(ob_integrator_t *itg) {
    itg->integral_deg_s = 0.0f;
}

/* Write coast (or duty_pct) through io unless that is what was written last; force writes anyway. */
static inline void ob_output_write(ob_output_t *out, const ob_motor_io_t *io, bool coast, float duty_pct,
                                   bool force) {
    bool same = out->valid && coast == out->coasting && (coast || duty_pct == out->duty_pct);
    if (!same || force) {
        if (coast) {
            if (io->write_coast != NULL) {
                io->write_coast(io->ctx);
            }
        } else if (io->write_duty != NULL) {
            io->write_duty(io->ctx, duty_pct);
        }
    }
    out->valid = true;
    out->coasting = coast;
    out->duty_pct = coast ? 0.0f : duty_pct;
}

static inline void ob_period_update(ob_period_t *p, uint32_t dt_ms) {
    if (dt_ms != p->dt_ms) {
        p->dt_ms = dt_ms;
        p->dt_s = 0.001f * (float)dt_ms;
        p->inv_dt = dt_ms > 0u ? 1000.0f / (float)dt_ms : 0.0f;
    }
}

/*
 * A command plans from the state of the last tick. When the next fresh
 * reading comes more than timeout_ms after the plan's start, the controller
 * was not being ticked (unsubscribed while another controller drove the
 * motor, or its caller stalled): the shaft may have been turned meanwhile and
 * the plan's start lies in the past, so following it would lunge at full duty
 * toward a target computed from a stale state. True then, once: the caller
 * plans the command again from this reading, starting now, at the speed it
 * was planned to start at (what the controller itself last did).
 */
bool ob_control_plan_stale(bool *plan_unconfirmed, uint32_t now_ms, uint32_t start_ms, uint32_t timeout_ms);

#endif /* OB_CONTROL_H */
