/*
 * One H-bridge channel driven from a signed duty: see hbridge.h.
 */
#include "hbridge.h"

#include <math.h>
#include <stddef.h>

#define TEXT(x) #x
#define NUMBER(x) TEXT(x)

void ob_hbridge_default_config(ob_hbridge_config_t *cfg, uint32_t freq_hz) {
    cfg->invert = false;
    cfg->freq_hz = freq_hz;
}

ob_hbridge_error_t ob_hbridge_check_config(const ob_hbridge_config_t *cfg) {
    if (cfg->freq_hz < (uint32_t)OB_HBRIDGE_FREQ_MIN_HZ || cfg->freq_hz > (uint32_t)OB_HBRIDGE_FREQ_MAX_HZ) {
        return OB_HBRIDGE_BAD_FREQ;
    }
    return OB_HBRIDGE_OK;
}

ob_hbridge_error_t ob_hbridge_init(ob_hbridge_t *hb, const ob_hbridge_config_t *cfg, const ob_hbridge_pins_t *pins) {
    ob_hbridge_error_t error = ob_hbridge_check_config(cfg);
    if (error != OB_HBRIDGE_OK) {
        return error;
    }
    if (pins != NULL && pins->write != NULL && (pins->duty_max == 0u || pins->duty_max > OB_HBRIDGE_DUTY_MAX_LIMIT)) {
        return OB_HBRIDGE_BAD_DUTY_MAX;
    }
    hb->cfg = *cfg;
    if (pins != NULL && pins->write != NULL) {
        hb->pins = *pins;
    } else {
        hb->pins = (ob_hbridge_pins_t){NULL, OB_HBRIDGE_UNWIRED_DUTY_MAX, NULL};
    }
    hb->levels_valid = false;
    hb->writes = 0;
    hb->write_errors = 0;
    ob_hbridge_coast(hb);
    return OB_HBRIDGE_OK;
}

ob_hbridge_levels_t ob_hbridge_levels_for(ob_hbridge_state_t state, float duty_pct, uint32_t duty_max) {
    switch (state) {
    case OB_HBRIDGE_FORWARD:
    case OB_HBRIDGE_REVERSE: {
        float share = duty_pct >= 100.0f ? 1.0f : (duty_pct > 0.0f ? duty_pct / 100.0f : 0.0f);
        uint32_t duty = (uint32_t)(share * (float)duty_max + 0.5f);
        return (ob_hbridge_levels_t){state == OB_HBRIDGE_FORWARD, state == OB_HBRIDGE_REVERSE,
                                     duty > duty_max ? duty_max : duty};
    }
    case OB_HBRIDGE_BRAKE:
        return (ob_hbridge_levels_t){true, true, duty_max};
    case OB_HBRIDGE_COAST:
        break;
    }
    return (ob_hbridge_levels_t){false, false, 0u};
}

static void apply(ob_hbridge_t *hb, ob_hbridge_state_t state, float duty_pct) {
    hb->state = state;
    hb->duty_pct = duty_pct;
    ob_hbridge_levels_t levels = ob_hbridge_levels_for(state, fabsf(duty_pct), hb->pins.duty_max);
    bool same = hb->levels_valid && levels.in1 == hb->levels.in1 && levels.in2 == hb->levels.in2 &&
                levels.duty == hb->levels.duty;
    hb->levels = levels;
    if (same) {
        return;
    }
    if (hb->pins.write != NULL && !hb->pins.write(hb->pins.ctx, levels.in1, levels.in2, levels.duty)) {
        hb->write_errors++;
        hb->levels_valid = false; /* the pins may hold anything now: the next call writes again */
        return;
    }
    hb->writes++;
    hb->levels_valid = true;
}

void ob_hbridge_drive(ob_hbridge_t *hb, float duty_pct) {
    if (isnan(duty_pct)) {
        ob_hbridge_coast(hb);
        return;
    }
    if (duty_pct == 0.0f) {
        ob_hbridge_brake(hb);
        return;
    }
    float duty = duty_pct > 100.0f ? 100.0f : (duty_pct < -100.0f ? -100.0f : duty_pct);
    bool forward = (duty > 0.0f) != hb->cfg.invert;
    apply(hb, forward ? OB_HBRIDGE_FORWARD : OB_HBRIDGE_REVERSE, duty);
}

void ob_hbridge_brake(ob_hbridge_t *hb) {
    apply(hb, OB_HBRIDGE_BRAKE, 0.0f);
}

void ob_hbridge_coast(ob_hbridge_t *hb) {
    apply(hb, OB_HBRIDGE_COAST, 0.0f);
}

void ob_hbridge_unwire(ob_hbridge_t *hb) {
    ob_hbridge_coast(hb);
    hb->pins.write = NULL;
    hb->pins.ctx = NULL;
}

uint32_t ob_hbridge_duty_max(const ob_hbridge_t *hb) {
    return hb->pins.duty_max;
}

void ob_hbridge_write_duty(void *ctx, float duty_pct) {
    ob_hbridge_drive(ctx, duty_pct);
}

void ob_hbridge_write_coast(void *ctx) {
    ob_hbridge_coast(ctx);
}

const char *ob_hbridge_state_name(ob_hbridge_state_t state) {
    switch (state) {
    case OB_HBRIDGE_COAST:
        return "coast";
    case OB_HBRIDGE_BRAKE:
        return "brake";
    case OB_HBRIDGE_FORWARD:
        return "forward";
    case OB_HBRIDGE_REVERSE:
        return "reverse";
    }
    return "unknown";
}

const char *ob_hbridge_strerror(ob_hbridge_error_t error) {
    switch (error) {
    case OB_HBRIDGE_OK:
        return "ok";
    case OB_HBRIDGE_BAD_FREQ:
        return "freq_hz must be " NUMBER(OB_HBRIDGE_FREQ_MIN_HZ) ".." NUMBER(OB_HBRIDGE_FREQ_MAX_HZ) " (an L298N runs at about 1000, a TB6612 at 20000)";
    case OB_HBRIDGE_BAD_DUTY_MAX:
        return "the PWM's duty_max must be 1..2^" NUMBER(OB_HBRIDGE_DUTY_BITS_MAX) " (2^resolution of its timer)";
    }
    return "unknown H-bridge error";
}
