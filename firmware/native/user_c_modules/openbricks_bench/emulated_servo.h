/*
 * Emulated ST-3032 / ST-3215 firmware behind an in-memory SCS wire, in
 * portable C: each servo's register file and the packets it answers (PING,
 * READ, WRITE, SYNC WRITE; broadcasts answered by no one), over a shaft its
 * user supplies. The one servo emulation in C: the simulator's ServoWire
 * (sim/native/servo_wire.c) puts it over MuJoCo wheels, the unix port's
 * bench bus (bench_servos.c) over a first-order shaft model. The register map
 * is the codec's (scs.h); a servo that is silent answers nothing.
 */
#ifndef OB_EMULATED_SERVO_H
#define OB_EMULATED_SERVO_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "scs.h"

#define OB_EMU_MAX_SERVOS 8

typedef struct {
    bool used;
    bool silent;
    uint8_t regs[OB_SCS_REG_COUNT];
} ob_emu_servo_t;

/* The shaft under every servo of a bus; index is the servo's place in ob_emu_bus_t.servos. */
typedef struct {
    /* Bring the shaft up to now_us before the servo reads it or applies a write (NULL: always current). */
    void (*advance)(void *ctx, int index, uint32_t now_us);
    /* Shaft position (counts, multi-turn, servo frame), speed (counts/s) and load (0.1 % of stall). */
    void (*sense)(void *ctx, int index, double *counts, double *speed_cps, double *load_permille);
    /* After a write of n registers from address: act on them (NULL: the shaft reads the registers). */
    void (*written)(void *ctx, int index, uint8_t address, size_t n);
    void *ctx;
} ob_emu_shaft_t;

typedef struct {
    ob_emu_servo_t servos[OB_EMU_MAX_SERVOS];
    ob_emu_shaft_t shaft;
    uint8_t reply[4u * OB_SCS_MAX_FRAME]; /* status replies waiting to be read */
    size_t reply_len;
    uint32_t packets; /* well-formed packets seen */
} ob_emu_bus_t;

void ob_emu_bus_init(ob_emu_bus_t *bus, ob_emu_shaft_t shaft);

/* A servo with id in wheel mode, torque off, single-turn limits 0..4095; -1 when full or taken. */
int ob_emu_bus_add(ob_emu_bus_t *bus, uint8_t id);

/* The index of the servo with id, or -1. */
int ob_emu_bus_find(const ob_emu_bus_t *bus, uint8_t id);

void ob_emu_bus_remove(ob_emu_bus_t *bus, int index);

/* Request bytes onto the wire at now_us: every whole frame in them is executed, replies queue. */
void ob_emu_bus_write(ob_emu_bus_t *bus, const uint8_t *data, size_t n, uint32_t now_us);

/* Up to cap reply bytes off the wire. */
size_t ob_emu_bus_read(ob_emu_bus_t *bus, uint8_t *buf, size_t cap);

/* True when a write of n registers from address covers reg. */
static inline bool ob_emu_touched(uint8_t address, size_t n, unsigned reg) {
    return address <= reg && reg < address + n;
}

#endif /* OB_EMULATED_SERVO_H */
