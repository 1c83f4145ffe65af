/*
 * Emulated ST-3032 servos on an in-memory wire (see bench_servos.h).
 */
#include "bench_servos.h"

#include <math.h>
#include <string.h>

#define DUTY_TAU_S 0.05      /* speed response to a duty or speed step */
#define FREEWHEEL_TAU_S 0.03 /* a coasting shaft behind the gearbox stops almost at once */
#define MAX_STEP_S 0.001     /* integration step */

/* The speed the shaft heads for, counts/s, and how fast it gets there. */
static double target_cps(const uint8_t *regs, double no_load_cps, double *tau_s) {
    *tau_s = DUTY_TAU_S;
    if (regs[OB_SCS_REG_TORQUE_ENABLE] == 0u) {
        *tau_s = FREEWHEEL_TAU_S;
        return 0.0;
    }
    if (regs[OB_SCS_REG_MODE] == OB_SCS_MODE_DUTY) {
        double duty = ob_scs_sm_decode(ob_scs_get_u16(&regs[OB_SCS_REG_GOAL_TIME]), OB_SCS_DUTY_SIGN_BIT) / 1000.0;
        return duty * no_load_cps;
    }
    if (regs[OB_SCS_REG_MODE] == OB_SCS_MODE_WHEEL) {
        double goal = ob_scs_sm_decode(ob_scs_get_u16(&regs[OB_SCS_REG_GOAL_SPEED]), OB_SCS_SPEED_SIGN_BIT);
        return fmax(-no_load_cps, fmin(no_load_cps, goal));
    }
    return 0.0; /* position and step modes: held where it is */
}

static void advance(ob_bench_servo_t *servo, double no_load_cps, uint32_t now_us) {
    double left_s = (double)(uint32_t)(now_us - servo->last_us) * 1e-6;
    servo->last_us = now_us;
    if (left_s > 1.0) {
        left_s = 1.0; /* a paused test: the shaft has long settled */
    }
    double tau_s;
    double target = target_cps(servo->firmware->regs, no_load_cps, &tau_s);
    while (left_s > 0.0) {
        double dt = left_s < MAX_STEP_S ? left_s : MAX_STEP_S;
        servo->speed_cps += (target - servo->speed_cps) * (dt / (tau_s + dt));
        servo->counts += servo->speed_cps * dt;
        left_s -= dt;
    }
}

/* The emulation's view of the shafts (ob_emu_shaft_t). */
static void shaft_advance(void *ctx, int index, uint32_t now_us) {
    ob_bench_bus_t *bus = ctx;
    advance(&bus->servos[index], bus->no_load_cps, now_us);
}

static void shaft_sense(void *ctx, int index, double *counts, double *speed_cps, double *load_permille) {
    const ob_bench_servo_t *servo = &((ob_bench_bus_t *)ctx)->servos[index];
    *counts = servo->counts;
    *speed_cps = servo->speed_cps;
    *load_permille = 0.0;
}

void ob_bench_bus_init(ob_bench_bus_t *bus, double no_load_dps) {
    memset(bus, 0, sizeof(*bus));
    ob_emu_bus_init(&bus->wire, (ob_emu_shaft_t){shaft_advance, shaft_sense, NULL, bus});
    bus->no_load_cps = no_load_dps * OB_SCS_COUNTS_PER_REV / 360.0;
}

ob_bench_servo_t *ob_bench_bus_add(ob_bench_bus_t *bus, uint8_t id, uint32_t now_us) {
    int index = ob_emu_bus_add(&bus->wire, id);
    if (index < 0) {
        return NULL;
    }
    ob_bench_servo_t *servo = &bus->servos[index];
    *servo = (ob_bench_servo_t){.firmware = &bus->wire.servos[index], .counts = 2048.0, .last_us = now_us};
    return servo;
}

ob_bench_servo_t *ob_bench_bus_find(ob_bench_bus_t *bus, uint8_t id) {
    int index = ob_emu_bus_find(&bus->wire, id);
    return index < 0 ? NULL : &bus->servos[index];
}

double ob_bench_servo_angle_deg(ob_bench_servo_t *servo, double no_load_cps, uint32_t now_us) {
    advance(servo, no_load_cps, now_us);
    return servo->counts * 360.0 / OB_SCS_COUNTS_PER_REV;
}
