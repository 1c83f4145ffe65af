/*
 * A quadrature encoder's position, counted by a wrapping hardware counter.
 *
 * The hardware (pcnt.h) counts edges of both channels (x4 decoding) into a
 * small counter that repeats every `modulus` counts: an ESP32 PCNT unit
 * returns to 0 at +-OB_PCNT_LIMIT, a plain 16-bit counter wraps at 65536.
 * Each sample takes the shortest way from the previous reading to the new
 * one modulo the counter's period, so the position is exact for any number
 * of wraps as long as the shaft moves fewer than modulus / 2 counts between
 * two samples (the hard tick samples every millisecond). The count is kept
 * in 64 bits: an MG370 at full speed would overflow 32 bits in under two
 * hours.
 *
 * Direction: forward is A leading B on the wire; `invert` flips it for an
 * encoder mounted mirror-image. Degrees are output-shaft degrees, the
 * manual's unit: counts_per_rev = 4 x PPR x gear ratio (1320 for a
 * JGB37-520 1:30, ~68028 for an MG370 1:34 GMR).
 */
#ifndef OB_ENCODER_H
#define OB_ENCODER_H

#include <stdbool.h>
#include <stdint.h>

#include "pcnt.h"

/* Largest counter period: a 16-bit counter's. */
#define OB_ENCODER_MODULUS_MAX 65536

typedef enum {
    OB_ENCODER_OK = 0,
    OB_ENCODER_BAD_COUNTS_PER_REV, /* counts_per_rev must be > 0 */
    OB_ENCODER_BAD_MODULUS,        /* modulus must be 4..65536 */
} ob_encoder_error_t;

typedef struct {
    int32_t counts_per_rev; /* edges per output-shaft turn (x4 decoding) */
    bool invert;            /* count down for the motor's forward */
    int32_t modulus;        /* the hardware counter reads the same value again every this many counts */
} ob_encoder_config_t;

typedef struct {
    ob_encoder_config_t cfg;
    ob_pcnt_t pcnt;      /* read: NULL when the owner feeds ob_encoder_sample itself */
    bool have_raw;
    int32_t last_raw;
    int64_t total;       /* counts since the first sample, in the counter's own direction */
    int64_t zero;        /* total at which count() reads 0 */
    int8_t direction;    /* sign of the last sample's movement, in the user's direction */
    uint32_t read_errors;
} ob_encoder_t;

/* A PCNT-driven encoder's defaults: modulus OB_PCNT_LIMIT, not inverted, counts_per_rev as given. */
void ob_encoder_default_config(ob_encoder_config_t *cfg, int32_t counts_per_rev);

/*
 * Start at count 0. pcnt may be NULL (samples come through ob_encoder_sample).
 * Nothing changes unless the config is valid.
 */
ob_encoder_error_t ob_encoder_init(ob_encoder_t *enc, const ob_encoder_config_t *cfg, const ob_pcnt_t *pcnt);

/* One reading of the hardware counter. The first one only sets where counting starts. */
void ob_encoder_sample(ob_encoder_t *enc, int32_t raw);

/* Read the counter through pcnt and sample it; false (and counted) when it could not be read. */
bool ob_encoder_poll(ob_encoder_t *enc);

/* Position in counts, in the user's direction, since the last reset. */
int64_t ob_encoder_count(const ob_encoder_t *enc);

/* Make the current position read `count`. */
void ob_encoder_reset_count(ob_encoder_t *enc, int64_t count);

/* Position in output-shaft degrees (count * 360 / counts_per_rev). */
float ob_encoder_angle_deg(const ob_encoder_t *enc);

/* +1 or -1: the direction of the last movement (user's frame); 0 when the last sample saw none. */
int ob_encoder_direction(const ob_encoder_t *enc);

/* Movement between two samples beyond which the unwrapping is ambiguous: (modulus - 1) / 2 counts. */
int32_t ob_encoder_max_step(const ob_encoder_t *enc);

/*
 * A motor IO's read_angle (ob_types.h) over an encoder (ctx: ob_encoder_t *):
 * polls the counter when it has one and returns the angle; false when the
 * counter could not be read.
 */
bool ob_encoder_read_angle(void *ctx, float *angle_deg);

/* Text for an ob_encoder_error_t, for the bindings' messages. */
const char *ob_encoder_strerror(ob_encoder_error_t error);

#endif /* OB_ENCODER_H */
