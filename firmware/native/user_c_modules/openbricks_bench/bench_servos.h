/*
 * Emulated ST-3032 servos behind an in-memory half-duplex SCS wire, in
 * portable C, for host tests of the serial-bus engine that must run while
 * the interpreter is busy (the hard tick on the unix port calls no Python).
 *
 * The servos' firmware is the shared emulation (emulated_servo.h: register
 * file, PING, READ, WRITE, SYNC WRITE); under it each servo has a shaft
 * modelled as a first-order speed response: in duty mode (2) towards the
 * duty's share of the no-load speed, in wheel mode (1) towards the goal
 * speed, decaying to rest while its torque is off; position and step modes
 * hold still. Replies are in as soon as the request is written.
 */
#ifndef OB_BENCH_SERVOS_H
#define OB_BENCH_SERVOS_H

#include <stdint.h>

#include "emulated_servo.h"

#define OB_BENCH_MAX_SERVOS OB_EMU_MAX_SERVOS

/* One servo's shaft; its firmware (register file, silent flag) is in the bus's wire. */
typedef struct {
    ob_emu_servo_t *firmware;
    double counts;    /* shaft position, multi-turn, servo frame */
    double speed_cps; /* shaft speed, counts/s */
    uint32_t last_us; /* when the shaft was last advanced */
} ob_bench_servo_t;

typedef struct {
    ob_emu_bus_t wire;
    ob_bench_servo_t servos[OB_EMU_MAX_SERVOS]; /* by the index of their firmware in the wire */
    double no_load_cps;                         /* shaft speed at 100 % duty */
} ob_bench_bus_t;

void ob_bench_bus_init(ob_bench_bus_t *bus, double no_load_dps);

/* A servo with id at rest, torque off, in wheel mode; NULL when full or the id is taken. */
ob_bench_servo_t *ob_bench_bus_add(ob_bench_bus_t *bus, uint8_t id, uint32_t now_us);

ob_bench_servo_t *ob_bench_bus_find(ob_bench_bus_t *bus, uint8_t id);

/* The servo's true shaft angle at now_us, degrees, servo frame. */
double ob_bench_servo_angle_deg(ob_bench_servo_t *servo, double no_load_cps, uint32_t now_us);

#endif /* OB_BENCH_SERVOS_H */
