/*
 * Quadrature encoder position from a wrapping hardware counter: see encoder.h.
 */
#include "encoder.h"

#include <stddef.h>

#define MODULUS_MIN 4

void ob_encoder_default_config(ob_encoder_config_t *cfg, int32_t counts_per_rev) {
    cfg->counts_per_rev = counts_per_rev;
    cfg->invert = false;
    cfg->modulus = OB_PCNT_LIMIT;
}

ob_encoder_error_t ob_encoder_init(ob_encoder_t *enc, const ob_encoder_config_t *cfg, const ob_pcnt_t *pcnt) {
    if (cfg->counts_per_rev <= 0) {
        return OB_ENCODER_BAD_COUNTS_PER_REV;
    }
    if (cfg->modulus < MODULUS_MIN || cfg->modulus > OB_ENCODER_MODULUS_MAX) {
        return OB_ENCODER_BAD_MODULUS;
    }
    enc->cfg = *cfg;
    if (pcnt != NULL) {
        enc->pcnt = *pcnt;
    } else {
        enc->pcnt.read = NULL;
        enc->pcnt.ctx = NULL;
    }
    enc->have_raw = false;
    enc->last_raw = 0;
    enc->total = 0;
    enc->zero = 0;
    enc->direction = 0;
    enc->read_errors = 0;
    return OB_ENCODER_OK;
}

/* The step from `from` to `to` the shaft most likely made: the difference modulo m, in -(m/2)..(m-1)/2. */
static int32_t shortest_step(int32_t from, int32_t to, int32_t m) {
    int64_t d = ((int64_t)to - (int64_t)from) % m;
    if (d < 0) {
        d += m;
    }
    if (d > (m - 1) / 2) {
        d -= m;
    }
    return (int32_t)d;
}

void ob_encoder_sample(ob_encoder_t *enc, int32_t raw) {
    if (!enc->have_raw) {
        enc->have_raw = true;
        enc->last_raw = raw;
        return;
    }
    int32_t step = shortest_step(enc->last_raw, raw, enc->cfg.modulus);
    enc->last_raw = raw;
    enc->total += step;
    int sign = enc->cfg.invert ? -1 : 1;
    enc->direction = (int8_t)(step > 0 ? sign : (step < 0 ? -sign : 0));
}

bool ob_encoder_poll(ob_encoder_t *enc) {
    int32_t raw;
    if (enc->pcnt.read == NULL || !enc->pcnt.read(enc->pcnt.ctx, &raw)) {
        enc->read_errors++;
        return false;
    }
    ob_encoder_sample(enc, raw);
    return true;
}

int64_t ob_encoder_count(const ob_encoder_t *enc) {
    int64_t count = enc->total - enc->zero;
    return enc->cfg.invert ? -count : count;
}

void ob_encoder_reset_count(ob_encoder_t *enc, int64_t count) {
    enc->zero = enc->total - (enc->cfg.invert ? -count : count);
}

float ob_encoder_angle_deg(const ob_encoder_t *enc) {
    /* Whole turns and the remainder apart: a float of the count alone would lose counts after 2^24. */
    int64_t count = ob_encoder_count(enc);
    int64_t turns = count / enc->cfg.counts_per_rev;
    int64_t rest = count % enc->cfg.counts_per_rev;
    return (float)turns * 360.0f + (float)rest * 360.0f / (float)enc->cfg.counts_per_rev;
}

int ob_encoder_direction(const ob_encoder_t *enc) {
    return enc->direction;
}

int32_t ob_encoder_max_step(const ob_encoder_t *enc) {
    return (enc->cfg.modulus - 1) / 2;
}

bool ob_encoder_read_angle(void *ctx, float *angle_deg) {
    ob_encoder_t *enc = ctx;
    if (enc->pcnt.read != NULL && !ob_encoder_poll(enc)) {
        return false;
    }
    *angle_deg = ob_encoder_angle_deg(enc);
    return true;
}

const char *ob_encoder_strerror(ob_encoder_error_t error) {
    switch (error) {
    case OB_ENCODER_OK:
        return "ok";
    case OB_ENCODER_BAD_COUNTS_PER_REV:
        return "counts_per_rev must be > 0 (4 x encoder PPR x gear ratio, e.g. 1320 for a JGB37-520 1:30)";
    case OB_ENCODER_BAD_MODULUS:
        return "modulus must be 4..65536 (the hardware counter's period: 32767 for a PCNT unit at +-32767)";
    }
    return "unknown encoder error";
}
