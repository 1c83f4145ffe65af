/*
 * The serial-bus engine: adopted SCS servos driven and read on the 1 kHz tick.
 * See serial_bus.h for the schedule and the contract.
 */
#include "serial_bus.h"

#include <math.h>
#include <string.h>

#include "scs.h"

#define DEG_PER_COUNT (360.0f / (float)OB_SERIAL_BUS_COUNTS_PER_REV)
#define MULTI_TURN_SPAN ((int32_t)OB_SCS_MULTI_TURN_SPAN)
#define FEEDBACK_BYTES 6u /* present position, speed and load */
/* A READ request, and its reply with the feedback bytes. */
#define READ_REQUEST_BYTES (OB_SCS_FRAME_OVERHEAD + 2u)
/* Received bytes one transaction looks at before giving up, whatever the wire's clock says. */
#define MAX_BYTES_PER_REPLY (4u * OB_SCS_MAX_FRAME)

static uint32_t now_us(const ob_serial_bus_t *bus) {
    return bus->uart.now_us(bus->uart.ctx);
}

static bool send(ob_serial_bus_t *bus, const uint8_t *packet, int n) {
    if (n <= 0) {
        return false;
    }
    bus->uart.flush_input(bus->uart.ctx); /* a late reply to an earlier request is not this one's */
    return bus->uart.write(bus->uart.ctx, packet, (size_t)n);
}

/*
 * Wait for the status reply of servo id carrying exactly param_len parameters.
 * Anything else on the wire (our own echo, garbage, a truncated frame, another
 * servo answering) is skipped; the wait ends at the deadline either way.
 */
static bool receive(ob_serial_bus_t *bus, uint8_t id, size_t param_len, uint8_t *params, uint8_t *status) {
    uint8_t buf[OB_SCS_MAX_FRAME];
    size_t len = 0;
    size_t seen = 0;
    const uint32_t start = now_us(bus);
    const uint32_t timeout_us = bus->reply_timeout_us;
    for (;;) {
        uint32_t elapsed = now_us(bus) - start;
        if (elapsed >= timeout_us || seen >= MAX_BYTES_PER_REPLY) {
            return false;
        }
        if (len == sizeof(buf)) {
            len = 0; /* cannot happen with a well-formed parse; never spin on a full buffer */
        }
        size_t n = bus->uart.read(bus->uart.ctx, buf + len, sizeof(buf) - len, timeout_us - elapsed);
        if (n == 0) {
            return false;
        }
        if (n > sizeof(buf) - len) {
            n = sizeof(buf) - len; /* a wire that claims more than it was given room for */
        }
        len += n;
        seen += n;
        while (len > 0) {
            ob_scs_frame_t frame;
            ob_scs_parse_t result = ob_scs_parse_status(buf, len, &frame);
            size_t consumed = frame.consumed;
            if (result == OB_SCS_PARSE_OK && frame.id == id && frame.param_len == param_len) {
                if (param_len > 0) {
                    memcpy(params, frame.params, param_len);
                }
                *status = frame.code;
                return true;
            }
            if (result != OB_SCS_PARSE_NEED_MORE) {
                bus->garbage_frames++;
                if (consumed == 0) {
                    consumed = 1;
                }
            }
            if (consumed > len) {
                consumed = len;
            }
            if (consumed == 0) {
                break; /* need more bytes */
            }
            memmove(buf, buf + consumed, len - consumed);
            len -= consumed;
            if (result == OB_SCS_PARSE_NEED_MORE) {
                break;
            }
        }
    }
}

/* One request and its reply, outside the tick: up to OB_SERIAL_BUS_ATTEMPTS tries. */
static bool transact(ob_serial_bus_t *bus, const uint8_t *packet, int n, uint8_t id, size_t param_len,
                     uint8_t *params) {
    uint8_t status;
    for (int attempt = 0; attempt < OB_SERIAL_BUS_ATTEMPTS; attempt++) {
        if (send(bus, packet, n) && receive(bus, id, param_len, params, &status)) {
            return true;
        }
    }
    return false;
}

static bool write_register(ob_serial_bus_t *bus, uint8_t id, uint8_t reg, const uint8_t *data, size_t n) {
    uint8_t packet[OB_SCS_FRAME_OVERHEAD + 8];
    int len = ob_scs_encode_write(id, reg, data, n, packet, sizeof(packet));
    return transact(bus, packet, len, id, 0, NULL);
}

static void take_feedback(ob_serial_bus_slot_t *slot, const uint8_t *data, uint8_t status) {
    int32_t raw = ob_scs_sm_decode(ob_scs_get_u16(data), OB_SCS_POSITION_SIGN_BIT);
    if (!slot->have_reading) {
        slot->counts = 0;
    } else {
        int32_t delta = raw - slot->last_raw;
        if (delta > MULTI_TURN_SPAN / 2) {
            delta -= MULTI_TURN_SPAN;
        } else if (delta < -(MULTI_TURN_SPAN / 2)) {
            delta += MULTI_TURN_SPAN;
        }
        slot->counts += delta;
    }
    slot->last_raw = raw;
    slot->have_reading = true;
    int32_t speed = ob_scs_sm_decode(ob_scs_get_u16(data + 2), OB_SCS_SPEED_SIGN_BIT);
    int32_t load = ob_scs_sm_decode(ob_scs_get_u16(data + 4), OB_SCS_LOAD_SIGN_BIT);
    slot->speed_dps = slot->sign * (float)speed * DEG_PER_COUNT;
    slot->load_pct = slot->sign * (float)load * 0.1f;
    slot->status = status;
    slot->replies++;
    slot->failed_in_a_row = 0;
}

static bool read_feedback(ob_serial_bus_t *bus, ob_serial_bus_slot_t *slot) {
    uint8_t packet[READ_REQUEST_BYTES];
    uint8_t data[FEEDBACK_BYTES];
    uint8_t status;
    int n = ob_scs_encode_read(slot->servo_id, OB_SCS_REG_PRESENT_POSITION, FEEDBACK_BYTES, packet, sizeof(packet));
    if (send(bus, packet, n) && receive(bus, slot->servo_id, FEEDBACK_BYTES, data, &status)) {
        take_feedback(slot, data, status);
        return true;
    }
    slot->failed_reads++;
    slot->failed_in_a_row++;
    return false;
}

void ob_serial_bus_init(ob_serial_bus_t *bus, const ob_uart_t *uart, uint32_t baud) {
    memset(bus, 0, sizeof(*bus));
    bus->uart = *uart;
    bus->byte_us = ob_uart_byte_us(baud == 0u ? OB_SERIAL_BUS_DEFAULT_BAUD : baud);
    bus->budget_us = OB_SERIAL_BUS_TICK_BUDGET_US;
    bus->reply_timeout_us = OB_SERIAL_BUS_REPLY_TIMEOUT_US;
}

ob_serial_bus_slot_t *ob_serial_bus_slot(ob_serial_bus_t *bus, int slot) {
    if (slot < 0 || slot >= bus->n_slots || !bus->slots[slot].adopted) {
        return NULL;
    }
    return &bus->slots[slot];
}

bool ob_serial_bus_active(const ob_serial_bus_t *bus) {
    for (int i = 0; i < bus->n_slots; i++) {
        if (bus->slots[i].adopted) {
            return true;
        }
    }
    return false;
}

ob_serial_bus_error_t ob_serial_bus_adopt(ob_serial_bus_t *bus, int servo_id, bool invert, int *slot_out) {
    if (servo_id < 0 || servo_id > (int)OB_SCS_MAX_SERVO_ID) {
        return OB_SERIAL_BUS_E_ID;
    }
    for (int i = 0; i < bus->n_slots; i++) {
        if (bus->slots[i].adopted && bus->slots[i].servo_id == (uint8_t)servo_id) {
            *slot_out = i;
            return OB_SERIAL_BUS_E_ADOPTED;
        }
    }
    if (!ob_serial_bus_active(bus)) {
        bus->n_slots = 0; /* every slot was released: numbering starts again */
        bus->next_read = 0;
    }
    if (bus->n_slots >= OB_SERIAL_BUS_MAX_SLOTS) {
        return OB_SERIAL_BUS_E_FULL;
    }
    uint8_t id = (uint8_t)servo_id;
    uint8_t packet[OB_SCS_FRAME_OVERHEAD];
    int n = ob_scs_encode_ping(id, packet, sizeof(packet));
    static const uint8_t off = 0u;
    static const uint8_t multi_turn[4] = {0u, 0u, 0u, 0u};
    static const uint8_t zero_duty[2] = {0u, 0u};
    static const uint8_t duty_mode = OB_SCS_MODE_DUTY;
    if (!transact(bus, packet, n, id, 0, NULL) || !write_register(bus, id, OB_SCS_REG_TORQUE_ENABLE, &off, 1) ||
        !write_register(bus, id, OB_SCS_REG_MIN_ANGLE, multi_turn, sizeof(multi_turn)) ||
        !write_register(bus, id, OB_SCS_REG_GOAL_TIME, zero_duty, sizeof(zero_duty)) ||
        !write_register(bus, id, OB_SCS_REG_MODE, &duty_mode, 1)) {
        return OB_SERIAL_BUS_E_SILENT;
    }
    ob_serial_bus_slot_t *slot = &bus->slots[bus->n_slots];
    memset(slot, 0, sizeof(*slot));
    slot->bus = bus;
    slot->servo_id = id;
    slot->sign = invert ? -1.0f : 1.0f;
    slot->torque_known = true; /* written off above */
    ob_servo_t *move = &bus->moves[bus->n_slots];
    ob_servo_config_default(&move->cfg); /* st_move_core's settings; the core starts with a move */
    move->cfg.counts_per_rev = (float)OB_SERIAL_BUS_COUNTS_PER_REV;
    bool answered = false;
    for (int attempt = 0; attempt < OB_SERIAL_BUS_ATTEMPTS && !answered; attempt++) {
        answered = read_feedback(bus, slot);
    }
    if (!answered) {
        return OB_SERIAL_BUS_E_SILENT;
    }
    slot->failed_reads = 0; /* the counters describe the adopted servo's life on the tick */
    slot->adopted = true;
    *slot_out = bus->n_slots++;
    return OB_SERIAL_BUS_OK;
}

ob_serial_bus_error_t ob_serial_bus_set_drive(ob_serial_bus_t *bus, int index, bool wheel_mode, float max_dps) {
    ob_serial_bus_slot_t *slot = ob_serial_bus_slot(bus, index);
    if (slot == NULL) {
        return OB_SERIAL_BUS_E_SLOT;
    }
    const uint8_t mode = wheel_mode ? OB_SCS_MODE_WHEEL : OB_SCS_MODE_DUTY;
    static const uint8_t zero[2] = {0u, 0u};
    /* The new mode's goal register starts at rest: the servo must not jump to a stale one. */
    const uint8_t setpoint_reg = wheel_mode ? OB_SCS_REG_GOAL_SPEED : OB_SCS_REG_GOAL_TIME;
    if (!write_register(bus, slot->servo_id, setpoint_reg, zero, sizeof(zero)) ||
        !write_register(bus, slot->servo_id, OB_SCS_REG_MODE, &mode, 1)) {
        return OB_SERIAL_BUS_E_SILENT;
    }
    slot->wheel_mode = wheel_mode;
    slot->wheel_max_dps = max_dps > 0.0f ? max_dps : 0.0f;
    return OB_SERIAL_BUS_OK;
}

ob_serial_bus_error_t ob_serial_bus_release(ob_serial_bus_t *bus, int index) {
    ob_serial_bus_slot_t *slot = ob_serial_bus_slot(bus, index);
    if (slot == NULL) {
        return OB_SERIAL_BUS_E_SLOT;
    }
    static const uint8_t off = 0u;
    static const uint8_t wheel_mode = OB_SCS_MODE_WHEEL;
    /* Best effort: a silent servo is released all the same. */
    (void)write_register(bus, slot->servo_id, OB_SCS_REG_TORQUE_ENABLE, &off, 1);
    (void)write_register(bus, slot->servo_id, OB_SCS_REG_MODE, &wheel_mode, 1);
    slot->adopted = false;
    slot->driven = false;
    slot->move_active = false;
    return OB_SERIAL_BUS_OK;
}

bool ob_serial_bus_answering(const ob_serial_bus_slot_t *slot) {
    return slot->have_reading && slot->failed_in_a_row < OB_SERIAL_BUS_SILENT_READS;
}

float ob_serial_bus_angle_deg(const ob_serial_bus_slot_t *slot) {
    return slot->sign * (float)slot->counts * DEG_PER_COUNT;
}

/* ---- Motor IO (user frame) ---- */

static bool io_read_angle(void *ctx, float *angle_deg) {
    const ob_serial_bus_slot_t *slot = ctx;
    if (!slot->adopted || !slot->have_reading || slot->failed_in_a_row > 0u) {
        return false;
    }
    *angle_deg = ob_serial_bus_angle_deg(slot);
    return true;
}

static void io_write_duty(void *ctx, float duty_pct) {
    ob_serial_bus_slot_t *slot = ctx;
    if (!(duty_pct == duty_pct)) {
        duty_pct = 0.0f; /* NaN: never send it */
    }
    slot->duty_pct = duty_pct > 100.0f ? 100.0f : duty_pct < -100.0f ? -100.0f : duty_pct;
    slot->driven = true;
}

static void io_write_coast(void *ctx) {
    ob_serial_bus_slot_t *slot = ctx;
    slot->driven = false;
    slot->duty_pct = 0.0f;
}

ob_motor_io_t ob_serial_bus_motor_io(ob_serial_bus_slot_t *slot) {
    ob_motor_io_t io = {io_read_angle, io_write_duty, io_write_coast, slot};
    return io;
}

/* ---- st_move_core ---- */

static ob_servo_t *move_of(const ob_serial_bus_slot_t *slot) {
    return &slot->bus->moves[slot - slot->bus->slots];
}

static ob_servo_t *start_move(ob_serial_bus_slot_t *slot) {
    ob_servo_t *move = move_of(slot);
    if (!slot->move_active) {
        /* A fresh core plans from the shaft's next reading, not from an earlier move's stale clock. */
        ob_servo_config_t cfg = move->cfg;
        ob_motor_io_t io = ob_serial_bus_motor_io(slot);
        ob_servo_init(move, &io, &cfg);
        slot->move_active = true;
    }
    return move;
}

void ob_serial_bus_move(ob_serial_bus_slot_t *slot, float speed_dps, float angle_deg, ob_then_t then,
                        float accel_dps2) {
    ob_servo_t *move = start_move(slot);
    float accel = accel_dps2 > 0.0f ? accel_dps2 : move->cfg.accel_dps2;
    float decel = accel_dps2 > 0.0f ? accel_dps2 : move->cfg.decel_dps2;
    ob_servo_move(move, speed_dps, angle_deg, true, then, accel, decel);
}

void ob_serial_bus_hold(ob_serial_bus_slot_t *slot) {
    ob_servo_hold(start_move(slot));
}

void ob_serial_bus_end_move(ob_serial_bus_slot_t *slot) {
    slot->move_active = false;
}

bool ob_serial_bus_arrived(const ob_serial_bus_slot_t *slot) {
    return !slot->move_active || ob_servo_is_done(move_of(slot));
}

bool ob_serial_bus_move_lost_feedback(const ob_serial_bus_slot_t *slot) {
    return slot->move_active && move_of(slot)->feedback_lost;
}

bool ob_serial_bus_stalled(const ob_serial_bus_slot_t *slot, float load_pct, float speed_dps) {
    if (!ob_serial_bus_answering(slot)) {
        return false;
    }
    if (slot->move_active && ob_servo_is_stalled(move_of(slot))) {
        return true;
    }
    return fabsf(slot->load_pct) >= load_pct && fabsf(slot->speed_dps) <= speed_dps;
}

/* ---- The tick ---- */

static void sync_write(ob_serial_bus_t *bus, uint8_t reg, uint8_t width, const uint8_t *ids, const uint8_t *data,
                       size_t count) {
    uint8_t packet[OB_SCS_FRAME_OVERHEAD + 2u + OB_SERIAL_BUS_MAX_SLOTS * 3u];
    if (count == 0) {
        return;
    }
    int n = ob_scs_encode_sync_write(reg, width, ids, data, count, packet, sizeof(packet));
    (void)send(bus, packet, n); /* nobody answers a sync write */
}

/* One sync write of the driven slots in one drive mode: duties (goal time) or wheel speeds (goal speed). */
static void send_goals(ob_serial_bus_t *bus, bool wheel_mode) {
    uint8_t ids[OB_SERIAL_BUS_MAX_SLOTS];
    uint8_t data[OB_SERIAL_BUS_MAX_SLOTS * 2];
    size_t count = 0;
    for (int i = 0; i < bus->n_slots; i++) {
        const ob_serial_bus_slot_t *slot = &bus->slots[i];
        if (slot->adopted && slot->driven && slot->wheel_mode == wheel_mode) {
            ids[count] = slot->servo_id;
            if (wheel_mode) {
                float steps = slot->sign * slot->duty_pct * 0.01f * slot->wheel_max_dps / DEG_PER_COUNT;
                ob_scs_put_u16(&data[2 * count], ob_scs_sm_encode((int32_t)lroundf(steps), OB_SCS_SPEED_SIGN_BIT));
            } else {
                float servo_duty = slot->sign * slot->duty_pct * 10.0f;
                ob_scs_put_u16(&data[2 * count], ob_scs_sm_encode((int32_t)lroundf(servo_duty), OB_SCS_DUTY_SIGN_BIT));
            }
            count++;
        }
    }
    sync_write(bus, wheel_mode ? OB_SCS_REG_GOAL_SPEED : OB_SCS_REG_GOAL_TIME, 2, ids, data, count);
}

static void send_commands(ob_serial_bus_t *bus) {
    uint8_t ids[OB_SERIAL_BUS_MAX_SLOTS];
    uint8_t data[OB_SERIAL_BUS_MAX_SLOTS * 2];
    size_t count = 0;
    send_goals(bus, false);
    send_goals(bus, true);
    /* Goals first: a servo switched on below starts on its new goal, not a stale one. */
    for (int i = 0; i < bus->n_slots; i++) {
        ob_serial_bus_slot_t *slot = &bus->slots[i];
        if (slot->adopted && (!slot->torque_known || slot->torque_on != slot->driven)) {
            ids[count] = slot->servo_id;
            data[count] = slot->driven ? 1u : 0u;
            slot->torque_known = true;
            slot->torque_on = slot->driven;
            count++;
        }
    }
    sync_write(bus, OB_SCS_REG_TORQUE_ENABLE, 1, ids, data, count);
}

void ob_serial_bus_tick(void *ctx, uint32_t now_ms) {
    ob_serial_bus_t *bus = ctx;
    if (bus->n_slots == 0) {
        return;
    }
    /* The slots' own moves and holds first, on the scheduler's clock: their duties go out below. */
    for (int i = 0; i < bus->n_slots; i++) {
        ob_serial_bus_slot_t *slot = &bus->slots[i];
        if (slot->adopted && slot->move_active) {
            ob_servo_tick(&bus->moves[i], now_ms);
        }
    }
    /* The bus work is measured on the wire's own clock. */
    const uint32_t start = now_us(bus);
    send_commands(bus);
    /* Worst case of one read: the request, then the whole reply deadline. */
    const uint32_t read_cost_us = READ_REQUEST_BYTES * bus->byte_us + bus->reply_timeout_us;
    int reads = 0;
    int next = bus->next_read % bus->n_slots;
    for (int k = 0; k < bus->n_slots; k++) {
        int i = (next + k) % bus->n_slots;
        ob_serial_bus_slot_t *slot = &bus->slots[i];
        if (!slot->adopted) {
            continue;
        }
        if (reads > 0 && now_us(bus) - start + read_cost_us > bus->budget_us) {
            bus->next_read = i; /* the next tick starts here */
            break;
        }
        reads++;
        if (!read_feedback(bus, slot) && now_us(bus) - start + read_cost_us <= bus->budget_us) {
            reads++; /* one retry while the budget allows; each failed attempt is counted */
            (void)read_feedback(bus, slot);
        }
    }
    bus->ticks++;
    bus->last_tick_bus_us = now_us(bus) - start;
    bus->bus_us_total += bus->last_tick_bus_us;
}

const char *ob_serial_bus_strerror(ob_serial_bus_error_t error) {
    switch (error) {
        case OB_SERIAL_BUS_OK:
            return "ok";
        case OB_SERIAL_BUS_E_ID:
            return "bus ids are 0..253 (254 is broadcast)";
        case OB_SERIAL_BUS_E_FULL:
            return "every slot of the engine is taken";
        case OB_SERIAL_BUS_E_ADOPTED:
            return "the servo is already adopted";
        case OB_SERIAL_BUS_E_SILENT:
            return "not responding on the bus";
        case OB_SERIAL_BUS_E_SLOT:
            return "not an adopted slot";
        case OB_SERIAL_BUS_E_COUNTS:
            return "an ST-3032/ST-3215 encoder has 4096 counts per turn";
    }
    return "unknown error";
}
