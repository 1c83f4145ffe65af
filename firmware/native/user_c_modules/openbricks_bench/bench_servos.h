/*
 * Emulated ST-3032 servos behind an in-memory half-duplex SCS wire, in
 * portable C, for host tests of the serial-bus engine that must run while
 * the interpreter is busy (the hard tick on the unix port calls no Python).
 *
 * Each servo has the STS register file and a shaft modelled as a
 * first-order speed response: in duty mode (2) towards the duty's share of
 * the no-load speed, in wheel mode (1) towards the goal speed, decaying to
 * rest while its torque is off; position and step modes hold still. It
 * answers PING, READ (present position, speed and load computed from the
 * shaft), WRITE and SYNC WRITE like the real firmware; a silent servo
 * answers nothing. Replies are in as soon as the request is written.
 */
#ifndef OB_BENCH_SERVOS_H
#define OB_BENCH_SERVOS_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "scs.h"

#define OB_BENCH_MAX_SERVOS 8
#define OB_BENCH_REGISTERS OB_SCS_REG_COUNT

typedef struct {
    bool used;
    bool silent;
    uint8_t regs[OB_BENCH_REGISTERS];
    double counts;      /* shaft position, multi-turn, servo frame */
    double speed_cps;   /* shaft speed, counts/s */
    uint32_t last_us;   /* when the shaft was last advanced */
} ob_bench_servo_t;

typedef struct {
    ob_bench_servo_t servos[OB_BENCH_MAX_SERVOS];
    double no_load_cps; /* shaft speed at 100 % duty */
    uint8_t reply[4u * OB_SCS_MAX_FRAME];
    size_t reply_len;
    uint32_t packets;
} ob_bench_bus_t;

void ob_bench_bus_init(ob_bench_bus_t *bus, double no_load_dps);

/* A servo with id at rest, torque off, in wheel mode; NULL when full or the id is taken. */
ob_bench_servo_t *ob_bench_bus_add(ob_bench_bus_t *bus, uint8_t id, uint32_t now_us);

ob_bench_servo_t *ob_bench_bus_find(ob_bench_bus_t *bus, uint8_t id);

/* Request bytes onto the wire at now_us: every whole frame is executed, replies queue for reading. */
void ob_bench_bus_write(ob_bench_bus_t *bus, const uint8_t *data, size_t n, uint32_t now_us);

/* Up to cap reply bytes off the wire. */
size_t ob_bench_bus_read(ob_bench_bus_t *bus, uint8_t *buf, size_t cap);

/* The servo's true shaft angle at now_us, degrees, servo frame. */
double ob_bench_servo_angle_deg(ob_bench_servo_t *servo, double no_load_cps, uint32_t now_us);

#endif /* OB_BENCH_SERVOS_H */
