/*
 * Trapezoidal / triangular speed profiles.
 *
 * Planning works in the direction of travel: distances and speeds are made
 * positive toward the target, so one set of formulas covers both directions,
 * then the sign is put back when the phases are stored.
 *
 * Sampling anchors phase 0 at the start and phases 1 and 2 at their ends.
 * The end of a move is therefore exact (a profile that ends at rest reads its
 * target, not target plus rounding), and a decelerating phase approaches its
 * end from behind, so rounding can never carry a sample past the target.
 */
#include "trajectory.h"

#include <math.h>

/* Moves shorter than this are already there: holding is indistinguishable
 * from moving, and it keeps raised decelerations finite. */
#define OB_TRAJECTORY_MIN_DISTANCE_DEG 1e-4f

static float sign_of(float x) {
    return x < 0.0f ? -1.0f : 1.0f;
}

/*
 * Store a profile given in the direction of travel: dir is +1 or -1, u0 the
 * start speed toward the target, v_peak the speed after phase 0, and the
 * phase durations. x_end is the position at the end of phase 2 (the target,
 * or the point where an end-at-cruise move reaches it); v_end the tail speed.
 */
static void store(ob_trajectory_t *tr, float x0, float dir, float u0, float a0, float dt0, float v_peak,
                  float dt1, float a2, float dt2, float x_end, float v_end) {
    tr->t_s[0] = dt0;
    tr->t_s[1] = dt0 + dt1;
    tr->t_s[2] = dt0 + dt1 + dt2;
    tr->a_dps2[0] = dir * a0;
    tr->a_dps2[1] = 0.0f;
    tr->a_dps2[2] = dir * a2;
    tr->v_dps[0] = dir * u0;
    tr->v_dps[1] = dir * v_peak;
    tr->v_dps[2] = dir * v_peak;
    tr->v_dps[3] = dir * v_end;
    tr->x_deg[0] = x0;
    tr->x_deg[3] = x_end;
    /* Phase 2 ends at x_end; step back over it (v_peak -> v_end at a2). */
    tr->x_deg[2] = x_end - dir * 0.5f * (v_peak + v_end) * dt2;
    /* Phase 0 starts at x0; its end is where the constant-speed phase 1 starts. */
    tr->x_deg[1] = x0 + dir * 0.5f * (u0 + v_peak) * dt0;
}

void ob_trajectory_plan_hold(ob_trajectory_t *tr, float x_deg) {
    for (int i = 0; i < 3; i++) {
        tr->t_s[i] = 0.0f;
        tr->a_dps2[i] = 0.0f;
    }
    for (int i = 0; i < 4; i++) {
        tr->x_deg[i] = x_deg;
        tr->v_dps[i] = 0.0f;
    }
}

void ob_trajectory_plan_speed(ob_trajectory_t *tr, float x0_deg, float v0_dps, float speed_dps,
                              float accel_dps2) {
    float dv = speed_dps - v0_dps;
    if (!(accel_dps2 > 0.0f) || dv == 0.0f) {
        /* No ramp to do (or no valid rate to do it at): cruise at the target speed now. */
        ob_trajectory_plan_hold(tr, x0_deg);
        tr->v_dps[0] = tr->v_dps[1] = tr->v_dps[2] = tr->v_dps[3] = speed_dps;
        return;
    }
    float dir = sign_of(dv);
    float dt0 = fabsf(dv) / accel_dps2;
    float x1 = x0_deg + 0.5f * (v0_dps + speed_dps) * dt0;
    tr->t_s[0] = tr->t_s[1] = tr->t_s[2] = dt0;
    tr->a_dps2[0] = dir * accel_dps2;
    tr->a_dps2[1] = tr->a_dps2[2] = 0.0f;
    tr->v_dps[0] = v0_dps;
    tr->v_dps[1] = tr->v_dps[2] = tr->v_dps[3] = speed_dps;
    tr->x_deg[0] = x0_deg;
    tr->x_deg[1] = tr->x_deg[2] = tr->x_deg[3] = x1;
}

/* Moves that end at rest on target. */
static void plan_to_rest(ob_trajectory_t *tr, float x0, float target, float dir, float distance, float u0,
                         float vmax, float accel, float decel) {
    float stop_distance = u0 > 0.0f ? u0 * u0 / (2.0f * decel) : 0.0f;
    if (u0 > 0.0f && distance <= stop_distance) {
        /* Too close to stop at decel: raise the deceleration just enough to
         * land at rest on target, in one phase, at the average speed u0 / 2. */
        float dt2 = 2.0f * distance / u0;
        store(tr, x0, dir, u0, 0.0f, 0.0f, u0, 0.0f, -u0 / dt2, dt2, target, 0.0f);
        return;
    }
    float v_peak;
    float a0;
    if (u0 > vmax) {
        /* Over-speed start: slow down to cruise at decel, cruise, then stop.
         * Reaching here means distance > u0^2 / (2 decel), so the cruise fits. */
        v_peak = vmax;
        a0 = decel;
    } else {
        /* Speed up from u0 (possibly moving away: phase 0 then passes through
         * zero at the same acceleration) toward cruise, or to the peak of a
         * triangle when the distance is too short to reach it. */
        float v_triangle_sq = (2.0f * accel * decel * distance + decel * u0 * u0) / (accel + decel);
        v_peak = v_triangle_sq < vmax * vmax ? sqrtf(v_triangle_sq) : vmax;
        if (u0 > 0.0f && v_peak < u0) {
            v_peak = u0; /* rounding at the triangle/raise boundary */
        }
        a0 = accel;
    }
    float dt0 = fabsf(v_peak - u0) / a0;
    float d0 = 0.5f * (u0 + v_peak) * dt0;
    float dt2 = v_peak / decel;
    float d2 = 0.5f * v_peak * dt2;
    float d1 = distance - d0 - d2;
    if (d1 < 0.0f && u0 + v_peak > 0.0f && distance > d2) {
        /*
         * No room to cruise, and the phases overshoot the distance by rounding alone. When v_peak
         * is close to u0, their difference keeps few significant bits, and divided by a small
         * acceleration that error is a visible step where phase 0 meets phase 2 (0.0005 deg for
         * 716 -> 716.002 deg/s at 13 deg/s^2). Phase 0 takes what distance is left instead, at the
         * acceleration that makes it end exactly at v_peak.
         */
        dt0 = 2.0f * (distance - d2) / (u0 + v_peak);
        a0 = dt0 > 0.0f ? fabsf(v_peak - u0) / dt0 : a0;
    }
    float dt1 = (d1 > 0.0f && v_peak > 0.0f) ? d1 / v_peak : 0.0f;
    store(tr, x0, dir, u0, u0 > v_peak ? -a0 : a0, dt0, v_peak, dt1, -decel, dt2, target, 0.0f);
}

/* Moves that end at target still moving (then="continue"). */
static void plan_to_cruise(ob_trajectory_t *tr, float x0, float target, float dir, float distance, float u0,
                           float vmax, float accel, float decel) {
    bool over_speed = u0 > vmax;
    float a0 = over_speed ? decel : accel;
    float ramp_distance = over_speed ? (u0 * u0 - vmax * vmax) / (2.0f * decel)
                                     : (vmax * vmax - u0 * u0) / (2.0f * accel);
    float v_peak = vmax;
    if (ramp_distance > distance) {
        /* Too short to reach cruise: arrive at whatever speed the ramp reached. */
        float v_sq = over_speed ? u0 * u0 - 2.0f * a0 * distance : u0 * u0 + 2.0f * a0 * distance;
        v_peak = sqrtf(v_sq > 0.0f ? v_sq : 0.0f);
    }
    float dt0 = fabsf(v_peak - u0) / a0;
    float d0 = 0.5f * (u0 + v_peak) * dt0;
    float d1 = distance - d0;
    float dt1 = (d1 > 0.0f && v_peak > 0.0f) ? d1 / v_peak : 0.0f;
    /* Phase 1 ends exactly on target; phase 2 is empty; the tail keeps v_peak. */
    store(tr, x0, dir, u0, u0 > v_peak ? -a0 : a0, dt0, v_peak, dt1, 0.0f, 0.0f, target, v_peak);
}

void ob_trajectory_plan_move(ob_trajectory_t *tr, float x0_deg, float v0_dps, float target_deg,
                             float speed_dps, float accel_dps2, float decel_dps2, bool end_at_cruise) {
    float vmax = fabsf(speed_dps);
    if (!(vmax > 0.0f) || !(accel_dps2 > 0.0f) || !(decel_dps2 > 0.0f)) {
        /* Not a move a motor can make (the bindings reject these first). */
        ob_trajectory_plan_hold(tr, target_deg);
        return;
    }
    float d = target_deg - x0_deg;
    float distance = fabsf(d);
    if (distance < OB_TRAJECTORY_MIN_DISTANCE_DEG) {
        if (end_at_cruise) {
            /* Already there: carry on at the current speed. */
            ob_trajectory_plan_hold(tr, target_deg);
            tr->v_dps[0] = tr->v_dps[1] = tr->v_dps[2] = tr->v_dps[3] = v0_dps;
            return;
        }
        if (v0_dps == 0.0f) {
            ob_trajectory_plan_hold(tr, target_deg);
            return;
        }
        /* Moving while on target: a move "toward" it starts by moving away,
         * so it turns around and comes back instead of stopping dead. Planned
         * from the target itself (a start this close counts as on it): the
         * forward phase and the phases sampled back from the target meet. */
        d = -v0_dps;
        distance = 0.0f;
        x0_deg = target_deg;
    }
    float dir = sign_of(d);
    float u0 = dir * v0_dps;
    if (end_at_cruise) {
        plan_to_cruise(tr, x0_deg, target_deg, dir, distance, u0, vmax, accel_dps2, decel_dps2);
    } else {
        plan_to_rest(tr, x0_deg, target_deg, dir, distance, u0, vmax, accel_dps2, decel_dps2);
    }
}

void ob_trajectory_sample(const ob_trajectory_t *tr, float t_s, ob_trajectory_sample_t *out) {
    if (t_s < 0.0f) {
        t_s = 0.0f;
    }
    if (t_s < tr->t_s[0]) {
        float a = tr->a_dps2[0];
        out->x_deg = tr->x_deg[0] + (tr->v_dps[0] + 0.5f * a * t_s) * t_s;
        out->v_dps = tr->v_dps[0] + a * t_s;
        out->a_dps2 = a;
    } else if (t_s < tr->t_s[2]) {
        /* Phases 1 and 2 are sampled back from their ends. */
        int i = t_s < tr->t_s[1] ? 1 : 2;
        float a = tr->a_dps2[i];
        float v_end = tr->v_dps[i + 1];
        float back = tr->t_s[i] - t_s;
        out->x_deg = tr->x_deg[i + 1] - (v_end - 0.5f * a * back) * back;
        out->v_dps = v_end - a * back;
        out->a_dps2 = a;
    } else {
        out->x_deg = tr->x_deg[3] + tr->v_dps[3] * (t_s - tr->t_s[2]);
        out->v_dps = tr->v_dps[3];
        out->a_dps2 = 0.0f;
    }
}

void ob_trajectory_scaled(const ob_trajectory_t *src, float k, float x0_deg, ob_trajectory_t *dst) {
    float origin = src->x_deg[0];
    for (int i = 0; i < 3; i++) {
        dst->t_s[i] = src->t_s[i];
        dst->a_dps2[i] = k * src->a_dps2[i];
    }
    for (int i = 0; i < 4; i++) {
        dst->x_deg[i] = x0_deg + k * (src->x_deg[i] - origin);
        dst->v_dps[i] = k * src->v_dps[i];
    }
}

float ob_trajectory_duration_s(const ob_trajectory_t *tr) {
    return tr->t_s[2];
}

float ob_trajectory_end_deg(const ob_trajectory_t *tr) {
    return tr->x_deg[3];
}
