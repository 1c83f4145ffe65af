/*
 * Speed profiles with explicit accel / cruise / decel phases (pbio
 * trajectory.c in spirit): trapezoidal, falling through to triangular when the
 * distance is too short to reach cruise speed.
 *
 * A profile is up to three constant-acceleration phases followed by a
 * constant-speed tail (zero for moves that end at rest, the cruise speed for
 * then="continue" and for speed ramps). Sampling is a pure function of time
 * since the profile's start, so a dropped control tick never dilates it.
 */
#ifndef OB_TRAJECTORY_H
#define OB_TRAJECTORY_H

#include <stdbool.h>

typedef struct {
    float t_s[3];     /* end time of phase 0, 1, 2, seconds since start */
    float x_deg[4];   /* position at start and at the end of each phase */
    float v_dps[4];   /* speed at start and at the end of each phase; v_dps[3] is the tail speed */
    float a_dps2[3];  /* constant acceleration within each phase */
} ob_trajectory_t;

typedef struct {
    float x_deg;
    float v_dps;
    float a_dps2;
} ob_trajectory_sample_t;

/*
 * Plan a move from (x0_deg, v0_dps) to target_deg.
 *
 * speed_dps, accel_dps2 and decel_dps2 are magnitudes (> 0). The start speed
 * may be non-zero, in either direction, or above speed_dps. When the move is
 * too short to stop at decel_dps2 from v0_dps, the deceleration is raised just
 * enough to land at rest on target. With end_at_cruise the profile has no
 * decel phase: it ends at target moving at cruise speed (or at the speed it
 * reached, if the distance is too short to reach cruise).
 */
void ob_trajectory_plan_move(ob_trajectory_t *tr, float x0_deg, float v0_dps, float target_deg,
                             float speed_dps, float accel_dps2, float decel_dps2, bool end_at_cruise);

/*
 * Plan a speed change: ramp from (x0_deg, v0_dps) to speed_dps (signed) at
 * accel_dps2 (magnitude), then hold that speed forever.
 */
void ob_trajectory_plan_speed(ob_trajectory_t *tr, float x0_deg, float v0_dps, float speed_dps,
                              float accel_dps2);

/* Hold still at x_deg: a profile whose every sample is (x_deg, 0, 0). */
void ob_trajectory_plan_hold(ob_trajectory_t *tr, float x_deg);

/* Sample the profile t_s seconds after its start (t_s < 0 reads the start). */
void ob_trajectory_sample(const ob_trajectory_t *tr, float t_s, ob_trajectory_sample_t *out);

/*
 * Make dst the profile src scaled by k in position offset, speed and
 * acceleration, starting at x0_deg, with src's phase times. Two profiles
 * related this way keep a fixed ratio at every instant: curve() plans the
 * forward profile and derives the heading profile with this, so the path is
 * a true circle through the ramps.
 */
void ob_trajectory_scaled(const ob_trajectory_t *src, float k, float x0_deg, ob_trajectory_t *dst);

/* Seconds from the start until the profile reaches its constant-speed tail. */
float ob_trajectory_duration_s(const ob_trajectory_t *tr);

/* Final position of a profile that ends at rest (its tail position). */
float ob_trajectory_end_deg(const ob_trajectory_t *tr);

#endif /* OB_TRAJECTORY_H */
