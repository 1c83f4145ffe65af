/*
 * Alpha-beta estimator: predict with constant speed, then split the residual
 * between position (alpha) and speed (beta / dt).
 *
 * It gives the controller a speed that is smooth at every speed a 4096-count
 * encoder can see, where finite differences jump by a whole count (88 deg/s
 * at 1 kHz) each time the reading moves. The price is a lag behind a changing
 * speed, which the servo covers with acceleration feed-forward.
 */
#include "observer.h"

#include <float.h>

static float gain_or(float gain, float fallback) {
    return (gain > 0.0f && gain <= 1.0f) ? gain : fallback;
}

void ob_observer_init(ob_observer_t *ob, float alpha, float beta) {
    ob->alpha = gain_or(alpha, OB_OBSERVER_DEFAULT_ALPHA);
    ob->beta = gain_or(beta, OB_OBSERVER_DEFAULT_BETA);
    ob_observer_reset(ob, 0.0f);
}

void ob_observer_reset(ob_observer_t *ob, float x_deg) {
    ob->x_deg = x_deg;
    ob->v_dps = 0.0f;
}

void ob_observer_update_inv(ob_observer_t *ob, float measured_deg, float dt_s, float inv_dt_s) {
    if (!(dt_s > 0.0f)) {
        return; /* no time has passed: the reading adds nothing to a speed estimate */
    }
    float predicted = ob->x_deg + ob->v_dps * dt_s;
    float residual = measured_deg - predicted;
    ob->x_deg = predicted + ob->alpha * residual;
    ob->v_dps += ob->beta * inv_dt_s * residual;
}

void ob_observer_update(ob_observer_t *ob, float measured_deg, float dt_s) {
    if (!(dt_s > 0.0f)) {
        return;
    }
    /* A denormal dt overflows 1 / dt: as good as no time passing, and an infinite gain would
     * turn the speed into inf, then NaN for good. */
    float inv_dt_s = 1.0f / dt_s;
    if (inv_dt_s <= FLT_MAX) {
        ob_observer_update_inv(ob, measured_deg, dt_s, inv_dt_s);
    }
}

void ob_observer_resync(ob_observer_t *ob, float measured_deg, float dt_s) {
    if (dt_s > 0.0f) {
        float v_dps = (measured_deg - ob->x_deg) / dt_s;
        ob->v_dps = (v_dps <= FLT_MAX && v_dps >= -FLT_MAX) ? v_dps : 0.0f;
    }
    ob->x_deg = measured_deg;
}

void ob_observer_predict(ob_observer_t *ob, float dt_s) {
    if (dt_s > 0.0f) {
        ob->x_deg += ob->v_dps * dt_s;
    }
}
