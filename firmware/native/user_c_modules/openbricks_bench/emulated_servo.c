/*
 * Emulated ST-3032 / ST-3215 firmware behind an SCS wire (see emulated_servo.h).
 */
#include "emulated_servo.h"

#include <math.h>
#include <string.h>

void ob_emu_bus_init(ob_emu_bus_t *bus, ob_emu_shaft_t shaft) {
    memset(bus, 0, sizeof(*bus));
    bus->shaft = shaft;
}

int ob_emu_bus_find(const ob_emu_bus_t *bus, uint8_t id) {
    for (int i = 0; i < OB_EMU_MAX_SERVOS; i++) {
        if (bus->servos[i].used && bus->servos[i].regs[OB_SCS_REG_ID] == id) {
            return i;
        }
    }
    return -1;
}

int ob_emu_bus_add(ob_emu_bus_t *bus, uint8_t id) {
    if (id > OB_SCS_MAX_SERVO_ID || ob_emu_bus_find(bus, id) >= 0) {
        return -1;
    }
    for (int i = 0; i < OB_EMU_MAX_SERVOS; i++) {
        ob_emu_servo_t *servo = &bus->servos[i];
        if (!servo->used) {
            memset(servo, 0, sizeof(*servo));
            servo->used = true;
            servo->regs[OB_SCS_REG_ID] = id;
            servo->regs[OB_SCS_REG_RESPONSE_LEVEL] = 1u;
            servo->regs[OB_SCS_REG_MODE] = OB_SCS_MODE_WHEEL;
            ob_scs_put_u16(&servo->regs[OB_SCS_REG_MAX_ANGLE], OB_SCS_COUNTS_PER_REV - 1u);
            ob_scs_put_u16(&servo->regs[OB_SCS_REG_MAX_TORQUE], 1000u);
            ob_scs_put_u16(&servo->regs[OB_SCS_REG_TORQUE_LIMIT], 1000u);
            return i;
        }
    }
    return -1;
}

void ob_emu_bus_remove(ob_emu_bus_t *bus, int index) {
    if (index >= 0 && index < OB_EMU_MAX_SERVOS) {
        bus->servos[index].used = false;
    }
}

/* Present position, speed and load into the register file, as the servo reports them. */
static void refresh_feedback(ob_emu_bus_t *bus, int index) {
    ob_emu_servo_t *servo = &bus->servos[index];
    double counts = 0.0, speed_cps = 0.0, load = 0.0;
    bus->shaft.sense(bus->shaft.ctx, index, &counts, &speed_cps, &load);
    bool multi_turn = ob_scs_get_u16(&servo->regs[OB_SCS_REG_MIN_ANGLE]) == 0u &&
                      ob_scs_get_u16(&servo->regs[OB_SCS_REG_MAX_ANGLE]) == 0u;
    counts = nearbyint(counts);
    int32_t position;
    if (multi_turn) {
        const double span = (double)OB_SCS_MULTI_TURN_SPAN, half = (double)(OB_SCS_MULTI_TURN_SPAN / 2u);
        double window = fmod(counts + half, span);
        position = (int32_t)(window < 0.0 ? window + span : window) - (int32_t)half;
    } else {
        double turn = fmod(counts, (double)OB_SCS_COUNTS_PER_REV);
        position = (int32_t)(turn < 0.0 ? turn + OB_SCS_COUNTS_PER_REV : turn);
    }
    ob_scs_put_u16(&servo->regs[OB_SCS_REG_PRESENT_POSITION], ob_scs_sm_encode(position, OB_SCS_POSITION_SIGN_BIT));
    ob_scs_put_u16(&servo->regs[OB_SCS_REG_PRESENT_SPEED],
                   ob_scs_sm_encode((int32_t)lround(speed_cps), OB_SCS_SPEED_SIGN_BIT));
    ob_scs_put_u16(&servo->regs[OB_SCS_REG_PRESENT_LOAD], ob_scs_sm_encode((int32_t)lround(load), OB_SCS_LOAD_SIGN_BIT));
}

static void advance(ob_emu_bus_t *bus, int index, uint32_t now_us) {
    if (bus->shaft.advance != NULL) {
        bus->shaft.advance(bus->shaft.ctx, index, now_us);
    }
}

static void write_registers(ob_emu_bus_t *bus, int index, uint8_t address, const uint8_t *data, size_t n,
                            uint32_t now_us) {
    advance(bus, index, now_us);
    ob_emu_servo_t *servo = &bus->servos[index];
    for (size_t i = 0; i < n && address + i < OB_SCS_REG_COUNT; i++) {
        servo->regs[address + i] = data[i];
    }
    if (bus->shaft.written != NULL) {
        bus->shaft.written(bus->shaft.ctx, index, address, n);
    }
}

static void reply(ob_emu_bus_t *bus, int index, const uint8_t *params, size_t n) {
    uint8_t id = bus->servos[index].regs[OB_SCS_REG_ID];
    int len = ob_scs_encode_status(id, 0u, params, n, bus->reply + bus->reply_len, sizeof(bus->reply) - bus->reply_len);
    if (len > 0) {
        bus->reply_len += (size_t)len;
    }
}

static void sync_write(ob_emu_bus_t *bus, const ob_scs_frame_t *frame, uint32_t now_us) {
    if (frame->param_len < 2u) {
        return;
    }
    uint8_t address = frame->params[0], width = frame->params[1];
    for (size_t i = 2; width > 0u && i + width < frame->param_len + 1u; i += (size_t)width + 1u) {
        int index = ob_emu_bus_find(bus, frame->params[i]);
        if (index >= 0 && !bus->servos[index].silent) {
            write_registers(bus, index, address, &frame->params[i + 1], width, now_us);
        }
    }
}

/* Broadcasts: every servo applies a WRITE, none replies; a lone servo answers a PING. */
static void broadcast(ob_emu_bus_t *bus, const ob_scs_frame_t *frame, uint32_t now_us) {
    int live = -1, n_live = 0;
    for (int i = 0; i < OB_EMU_MAX_SERVOS; i++) {
        if (!bus->servos[i].used || bus->servos[i].silent) {
            continue;
        }
        live = i;
        n_live++;
        if (frame->code == OB_SCS_INSTR_WRITE && frame->param_len >= 1u) {
            write_registers(bus, i, frame->params[0], &frame->params[1], frame->param_len - 1u, now_us);
        }
    }
    if (frame->code == OB_SCS_INSTR_PING && n_live == 1) {
        reply(bus, live, NULL, 0); /* several would collide into garbage */
    }
}

static void execute(ob_emu_bus_t *bus, const ob_scs_frame_t *frame, uint32_t now_us) {
    bus->packets++;
    if (frame->code == OB_SCS_INSTR_SYNC_WRITE) {
        sync_write(bus, frame, now_us);
        return;
    }
    if (frame->id == OB_SCS_BROADCAST_ID) {
        broadcast(bus, frame, now_us);
        return;
    }
    int index = ob_emu_bus_find(bus, frame->id);
    if (index < 0 || bus->servos[index].silent) {
        return;
    }
    if (frame->code == OB_SCS_INSTR_READ) {
        if (frame->param_len != 2u || frame->params[0] + (size_t)frame->params[1] > OB_SCS_REG_COUNT) {
            return;
        }
        advance(bus, index, now_us);
        refresh_feedback(bus, index);
        reply(bus, index, &bus->servos[index].regs[frame->params[0]], frame->params[1]);
    } else if (frame->code == OB_SCS_INSTR_WRITE) {
        if (frame->param_len < 1u) {
            return;
        }
        write_registers(bus, index, frame->params[0], &frame->params[1], frame->param_len - 1u, now_us);
        /* A new id answers from the new id, the register file says; the index is the same servo. */
        if (bus->servos[index].regs[OB_SCS_REG_RESPONSE_LEVEL] >= 1u) {
            reply(bus, index, NULL, 0);
        }
    } else if (frame->code == OB_SCS_INSTR_PING) {
        reply(bus, index, NULL, 0);
    }
}

void ob_emu_bus_write(ob_emu_bus_t *bus, const uint8_t *data, size_t n, uint32_t now_us) {
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

size_t ob_emu_bus_read(ob_emu_bus_t *bus, uint8_t *buf, size_t cap) {
    size_t n = bus->reply_len < cap ? bus->reply_len : cap;
    memcpy(buf, bus->reply, n);
    memmove(bus->reply, bus->reply + n, bus->reply_len - n);
    bus->reply_len -= n;
    return n;
}
