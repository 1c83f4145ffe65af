/*
 * The shared feedback law: see control.h for the rules and why. What runs
 * every tick is inline in control.h, so each loop's update compiles into one
 * function as before (on the hub a call costs more than these bodies); what
 * runs when a loop is configured or a command is confirmed is here.
 */
#include "control.h"

void ob_integrator_set_limit(ob_integrator_t *itg, const ob_control_gains_t *g, float duty_limit_pct) {
    float limit = g->integral_limit_pct < duty_limit_pct ? g->integral_limit_pct : duty_limit_pct;
    itg->max_deg_s = g->ki_pct_per_deg_s > 0.0f ? limit / g->ki_pct_per_deg_s : 0.0f;
}

bool ob_control_plan_stale(bool *plan_unconfirmed, uint32_t now_ms, uint32_t start_ms, uint32_t timeout_ms) {
    if (!*plan_unconfirmed) {
        return false;
    }
    *plan_unconfirmed = false;
    return (uint32_t)(now_ms - start_ms) > timeout_ms;
}
