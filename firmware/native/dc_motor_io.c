/*
 * A DC gear motor's encoder-in, bridge-out IO: see dc_motor_io.h.
 */
#include "dc_motor_io.h"

#include <math.h>
#include <stddef.h>

bool ob_dc_motor_io_init(ob_dc_motor_io_t *io, ob_encoder_t *encoder, ob_hbridge_t *bridge, double deg_per_count) {
    if (!isfinite(deg_per_count) || deg_per_count <= 0.0) {
        return false;
    }
    io->encoder = encoder;
    io->bridge = bridge;
    io->deg_per_count = deg_per_count;
    return true;
}

static bool read_angle(void *ctx, float *angle_deg) {
    ob_dc_motor_io_t *io = ctx;
    if (io->encoder->pcnt.read != NULL && !ob_encoder_poll(io->encoder)) {
        return false;
    }
    *angle_deg = (float)((double)ob_encoder_count(io->encoder) * io->deg_per_count);
    return true;
}

static void write_duty(void *ctx, float duty_pct) {
    ob_hbridge_drive(((ob_dc_motor_io_t *)ctx)->bridge, duty_pct);
}

static void write_coast(void *ctx) {
    ob_hbridge_coast(((ob_dc_motor_io_t *)ctx)->bridge);
}

ob_motor_io_t ob_dc_motor_io(ob_dc_motor_io_t *io) {
    return (ob_motor_io_t){read_angle, write_duty, write_coast, io};
}
