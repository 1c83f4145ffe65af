/*
 * Emulated ST-3032 servos on an in-memory wire (see bench_servos.h).
 */
#include "bench_servos.h"

#include <math.h>
#include <string.h>

#define COUNTS_PER_REV ((double)OB_SCS_COUNTS_PER_REV)
#define MULTI_TURN_SPAN ((double)OB_SCS_MULTI_TURN_SPAN)
#define DUTY_TAU_S 0.05     /* speed response to a duty or speed step */
#define FREEWHEEL_TAU_S 0.03 /* a coasting shaft behind the gearbox stops almost at once */
#define MAX_STEP_S 0.001    /* integration step */

void ob_bench_bus_init(ob_bench_bus_t *bus, double no_load_dps) {
    memset(bus, 0, sizeof(*bus));
    bus->no_load_cps = no_load_dps * COUNTS_PER_REV / 360.0;
}

ob_bench_servo_t *ob_bench_bus_find(ob_bench_bus_t *bus, uint8_t id) {
    for (int i = 0; i < OB_BENCH_MAX_SERVOS; i++) {
        if (bus->servos[i].used && bus->servos[i].regs[OB_SCS_REG_ID] == id) {
            return &bus->servos[i];
        }
    }
    return NULL;
}

ob_bench_servo_t *ob_bench_bus_add(ob_bench_bus_t *bus, uint8_t id, uint32_t now_us) {
    if (id > OB_SCS_MAX_SERVO_ID || ob_bench_bus_find(bus, id) != NULL) {
        return NULL;
    }
    for (int i = 0; i < OB_BENCH_MAX_SERVOS; i++) {
        ob_bench_servo_t *servo = &bus->servos[i];
        if (!servo->used) {
            memset(servo, 0, sizeof(*servo));
            servo->used = true;
            servo->regs[OB_SCS_REG_ID] = id;
            servo->regs[OB_SCS_REG_MODE] = OB_SCS_MODE_WHEEL;
            ob_scs_put_u16(&servo->regs[OB_SCS_REG_MAX_ANGLE], 4095u);
            servo->counts = 2048.0;
            servo->last_us = now_us;
            return servo;
        }
    }
    return NULL;
}

/* The speed the shaft heads for, counts/s, and how fast it gets there. */
static double target_cps(const ob_bench_servo_t *servo, double no_load_cps, double *tau_s) {
    *tau_s = DUTY_TAU_S;
    if (servo->regs[OB_SCS_REG_TORQUE_ENABLE] == 0u) {
        *tau_s = FREEWHEEL_TAU_S;
        return 0.0;
    }
    if (servo->regs[OB_SCS_REG_MODE] == OB_SCS_MODE_DUTY) {
        uint16_t raw = ob_scs_get_u16(&servo->regs[OB_SCS_REG_GOAL_TIME]);
        double duty = ob_scs_sm_decode(raw, OB_SCS_DUTY_SIGN_BIT) / 1000.0;
        return duty * no_load_cps;
    }
    if (servo->regs[OB_SCS_REG_MODE] == OB_SCS_MODE_WHEEL) {
        double goal = ob_scs_sm_decode(ob_scs_get_u16(&servo->regs[OB_SCS_REG_GOAL_SPEED]), OB_SCS_SPEED_SIGN_BIT);
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
    double target = target_cps(servo, no_load_cps, &tau_s);
    while (left_s > 0.0) {
        double dt = left_s < MAX_STEP_S ? left_s : MAX_STEP_S;
        servo->speed_cps += (target - servo->speed_cps) * (dt / (tau_s + dt));
        servo->counts += servo->speed_cps * dt;
        left_s -= dt;
    }
}

double ob_bench_servo_angle_deg(ob_bench_servo_t *servo, double no_load_cps, uint32_t now_us) {
    advance(servo, no_load_cps, now_us);
    return servo->counts * 360.0 / COUNTS_PER_REV;
}

/* Present position, speed and load into the register file, as the servo reports them. */
static void refresh_feedback(ob_bench_servo_t *servo) {
    bool multi_turn = ob_scs_get_u16(&servo->regs[OB_SCS_REG_MIN_ANGLE]) == 0u &&
                      ob_scs_get_u16(&servo->regs[OB_SCS_REG_MAX_ANGLE]) == 0u;
    double counts = nearbyint(servo->counts);
    int32_t position;
    if (multi_turn) {
        double window = fmod(counts + 32767.0, MULTI_TURN_SPAN);
        position = (int32_t)(window < 0.0 ? window + MULTI_TURN_SPAN : window) - 32767;
    } else {
        double turn = fmod(counts, COUNTS_PER_REV);
        position = (int32_t)(turn < 0.0 ? turn + COUNTS_PER_REV : turn);
    }
    ob_scs_put_u16(&servo->regs[OB_SCS_REG_PRESENT_POSITION], ob_scs_sm_encode(position, OB_SCS_POSITION_SIGN_BIT));
    ob_scs_put_u16(&servo->regs[OB_SCS_REG_PRESENT_SPEED],
                   ob_scs_sm_encode((int32_t)lround(servo->speed_cps), OB_SCS_SPEED_SIGN_BIT));
    ob_scs_put_u16(&servo->regs[OB_SCS_REG_PRESENT_LOAD], 0u);
}

static void write_registers(ob_bench_servo_t *servo, uint8_t address, const uint8_t *data, size_t n) {
    for (size_t i = 0; i < n && address + i < OB_BENCH_REGISTERS; i++) {
        servo->regs[address + i] = data[i];
    }
}

static void reply(ob_bench_bus_t *bus, uint8_t id, const uint8_t *params, size_t n) {
    int len = ob_scs_encode_status(id, 0u, params, n, bus->reply + bus->reply_len,
                                   sizeof(bus->reply) - bus->reply_len);
    if (len > 0) {
        bus->reply_len += (size_t)len;
    }
}

static void execute(ob_bench_bus_t *bus, const ob_scs_frame_t *frame, uint32_t now_us) {
    bus->packets++;
    if (frame->code == OB_SCS_INSTR_SYNC_WRITE) {
        if (frame->param_len < 2u) {
            return;
        }
        uint8_t address = frame->params[0], width = frame->params[1];
        for (size_t i = 2; width > 0u && i + width < frame->param_len + 1u; i += (size_t)width + 1u) {
            ob_bench_servo_t *servo = ob_bench_bus_find(bus, frame->params[i]);
            if (servo != NULL && !servo->silent) {
                advance(servo, bus->no_load_cps, now_us);
                write_registers(servo, address, &frame->params[i + 1], width);
            }
        }
        return;
    }
    ob_bench_servo_t *servo = ob_bench_bus_find(bus, frame->id);
    if (servo == NULL || servo->silent) {
        return;
    }
    advance(servo, bus->no_load_cps, now_us);
    uint8_t id = frame->id;
    if (frame->code == OB_SCS_INSTR_READ) {
        if (frame->param_len != 2u || frame->params[0] + (size_t)frame->params[1] > OB_BENCH_REGISTERS) {
            return;
        }
        refresh_feedback(servo);
        reply(bus, id, &servo->regs[frame->params[0]], frame->params[1]);
    } else if (frame->code == OB_SCS_INSTR_WRITE) {
        if (frame->param_len < 1u) {
            return;
        }
        write_registers(servo, frame->params[0], &frame->params[1], frame->param_len - 1u);
        reply(bus, id, NULL, 0);
    } else if (frame->code == OB_SCS_INSTR_PING) {
        reply(bus, id, NULL, 0);
    }
}

void ob_bench_bus_write(ob_bench_bus_t *bus, const uint8_t *data, size_t n, uint32_t now_us) {
    size_t offset = 0;
    while (offset < n) {
        ob_scs_frame_t frame;
        ob_scs_parse_t result = ob_scs_parse_frame(data + offset, n - offset, &frame);
        if (result == OB_SCS_PARSE_OK) {
            execute(bus, &frame, now_us);
        }
        if (frame.consumed == 0 || result == OB_SCS_PARSE_NEED_MORE) {
            break;
        }
        offset += frame.consumed;
    }
}

size_t ob_bench_bus_read(ob_bench_bus_t *bus, uint8_t *buf, size_t cap) {
    size_t n = bus->reply_len < cap ? bus->reply_len : cap;
    memcpy(buf, bus->reply, n);
    memmove(bus->reply, bus->reply + n, bus->reply_len - n);
    bus->reply_len -= n;
    return n;
}
