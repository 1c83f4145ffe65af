/*
 * A DC gear motor's IO as a controller sees it (ob_types.h): the encoder
 * core's count in, an H-bridge channel out.
 *
 * This is what lets a JGB37-520 or MG370 wheel be ticked with no Python
 * call: the hub's hard tick keeps the encoder counting (encoder.h) and the
 * controller writes the bridge's pins (hbridge.h) from C, the way a
 * serial-bus slot's IO does for a servo.
 *
 * Angles are output-shaft degrees: count x deg_per_count, where
 * deg_per_count is 360 / counts per output turn (a calibrated, fractional
 * figure is kept exactly; the count is scaled in double so a wheel that has
 * turned for hours still reads to the count).
 */
#ifndef OB_DC_MOTOR_IO_H
#define OB_DC_MOTOR_IO_H

#include <stdbool.h>

#include "encoder.h"
#include "hbridge.h"
#include "ob_types.h"

typedef struct {
    ob_encoder_t *encoder;
    ob_hbridge_t *bridge;
    double deg_per_count;
} ob_dc_motor_io_t;

/* Join encoder and bridge; false (nothing changed) unless deg_per_count is finite and > 0. */
bool ob_dc_motor_io_init(ob_dc_motor_io_t *io, ob_encoder_t *encoder, ob_hbridge_t *bridge, double deg_per_count);

/* The controller's view: read_angle polls the encoder's counter when it has one; the writes drive the bridge. */
ob_motor_io_t ob_dc_motor_io(ob_dc_motor_io_t *io);

#endif /* OB_DC_MOTOR_IO_H */
