/*
 * SerialBus: the serial-bus engine (serial_bus.c) for MicroPython (host: py_serial_bus.c).
 *
 * SerialBus(uart, baud=1000000) runs the engine over a Python UART (an object
 * with write(bytes), read(n) -> bytes or None and any(): machine.UART, or the
 * tests' fake bus of scripted servos). Replies there are in as soon as the
 * request is written, so the adapter keeps the wire's clock itself: each byte
 * costs its time at baud, and a read that finds nothing costs the whole wait.
 * On the hub, serial_bus() builds the engine over ESP-IDF's UART driver
 * instead (mp_uart_esp32.c), which never calls Python; on host builds a
 * native UART object (an in-memory bus of a test) does the same. An engine
 * over a wire that never calls Python is hard-safe: the hard tick runs it
 * from the timer's context (mp_scheduler.c), and its methods, like its
 * slots' motor IO, are called under the motor lock (mp_hard_lock.c).
 *
 * The engine subscribes itself to motor_process when it adopts its first
 * servo and unsubscribes when the last one is released. An exception from a
 * Python UART during a tick is kept and raised by motor_process after the
 * round, as for the other subscribers.
 */
#include <string.h>

#include "mp_bindings.h"
#include "py/mperrno.h"
#include "serial_bus.h"

typedef struct {
    ob_mp_subscriber_t sub;
    ob_serial_bus_t bus;
    mp_obj_t uart;
    uint32_t clock_us;
    uint32_t byte_us;
} serial_bus_obj_t;

/* A slot's motor IO: a MotorIO (its functions never call Python), so a controller over it is hard-safe. */
typedef struct {
    ob_mp_motor_io_t base;
    serial_bus_obj_t *owner;
} slot_io_obj_t;

static const mp_obj_type_t slot_io_type;

/* ---- A Python UART as an ob_uart_t ---- */

static bool py_write(void *ctx, const uint8_t *data, size_t n) {
    serial_bus_obj_t *self = ctx;
    self->clock_us += (uint32_t)n * self->byte_us;
    if (self->sub.error != MP_OBJ_NULL) {
        return false; /* no Python call while an error waits to be raised */
    }
    nlr_buf_t nlr;
    if (nlr_push(&nlr) == 0) {
        mp_obj_t dest[3];
        mp_load_method(self->uart, MP_QSTR_write, dest);
        dest[2] = mp_obj_new_bytes(data, n);
        mp_call_method_n_kw(1, 0, dest);
        nlr_pop();
        return true;
    }
    ob_mp_subscriber_stash(&self->sub, MP_OBJ_FROM_PTR(nlr.ret_val));
    return false;
}

static size_t py_read(void *ctx, uint8_t *buf, size_t cap, uint32_t timeout_us) {
    serial_bus_obj_t *self = ctx;
    size_t n = 0;
    if (self->sub.error == MP_OBJ_NULL) {
        nlr_buf_t nlr;
        if (nlr_push(&nlr) == 0) {
            mp_obj_t dest[3];
            mp_load_method(self->uart, MP_QSTR_read, dest);
            dest[2] = MP_OBJ_NEW_SMALL_INT((mp_int_t)cap);
            mp_obj_t data = mp_call_method_n_kw(1, 0, dest);
            if (data != mp_const_none) {
                mp_buffer_info_t info;
                mp_get_buffer_raise(data, &info, MP_BUFFER_READ);
                n = info.len < cap ? info.len : cap;
                memcpy(buf, info.buf, n);
            }
            nlr_pop();
        } else {
            ob_mp_subscriber_stash(&self->sub, MP_OBJ_FROM_PTR(nlr.ret_val));
        }
    }
    self->clock_us += n > 0 ? (uint32_t)n * self->byte_us : timeout_us;
    return n;
}

static void py_flush_input(void *ctx) {
    serial_bus_obj_t *self = ctx;
    if (self->sub.error != MP_OBJ_NULL) {
        return;
    }
    nlr_buf_t nlr;
    if (nlr_push(&nlr) == 0) {
        mp_obj_t dest[2];
        mp_load_method(self->uart, MP_QSTR_any, dest);
        if (mp_obj_is_true(mp_call_method_n_kw(0, 0, dest))) {
            mp_load_method(self->uart, MP_QSTR_read, dest);
            mp_call_method_n_kw(0, 0, dest);
        }
        nlr_pop();
    } else {
        ob_mp_subscriber_stash(&self->sub, MP_OBJ_FROM_PTR(nlr.ret_val));
    }
}

static uint32_t py_now_us(void *ctx) {
    return ((serial_bus_obj_t *)ctx)->clock_us;
}

/* ---- The engine ---- */

static void serial_bus_tick_fn(void *ctx, uint32_t now_ms) {
    serial_bus_obj_t *self = ctx;
    ob_serial_bus_tick(&self->bus, now_ms); /* UART errors stay in sub.error for motor_process */
}

static serial_bus_obj_t *new_engine(const mp_obj_type_t *type, mp_obj_t uart, const ob_uart_t *native,
                                    uint32_t baud) {
    if (baud < 9600u || baud > 4000000u) {
        mp_raise_msg_varg(&mp_type_ValueError, MP_ERROR_TEXT("SerialBus(): baud=%u is outside 9600..4000000"),
                          (unsigned)baud);
    }
    serial_bus_obj_t *self = mp_obj_malloc(serial_bus_obj_t, type);
    self->sub.error = MP_OBJ_NULL;
    self->uart = uart;
    self->clock_us = 0;
    self->byte_us = ob_uart_byte_us(baud);
    ob_uart_t wire = {py_write, py_read, py_flush_input, py_now_us, self};
    ob_serial_bus_init(&self->bus, native != NULL ? native : &wire, baud);
    self->sub.tick_fn = serial_bus_tick_fn;
    self->sub.tick_ctx = self;
    self->sub.hard_safe = native != NULL;
    return self;
}

static mp_obj_t serial_bus_make_new(const mp_obj_type_t *type, size_t n_args, size_t n_kw, const mp_obj_t *args) {
    enum { ARG_uart, ARG_baud };
    static const mp_arg_t allowed[] = {
        {MP_QSTR_uart, MP_ARG_REQUIRED | MP_ARG_OBJ, {.u_obj = MP_OBJ_NULL}},
        {MP_QSTR_baud, MP_ARG_INT, {.u_int = OB_SERIAL_BUS_DEFAULT_BAUD}},
    };
    mp_arg_val_t vals[MP_ARRAY_SIZE(allowed)];
    mp_arg_parse_all_kw_array(n_args, n_kw, args, MP_ARRAY_SIZE(allowed), allowed, vals);
    mp_obj_t uart = vals[ARG_uart].u_obj;
    const ob_uart_t *native = ob_mp_native_uart_get(uart);
    if (native != NULL) {
        return MP_OBJ_FROM_PTR(new_engine(type, uart, native, (uint32_t)vals[ARG_baud].u_int));
    }
    static const qstr needed[] = {MP_QSTR_write, MP_QSTR_read, MP_QSTR_any};
    for (size_t i = 0; i < MP_ARRAY_SIZE(needed); i++) {
        mp_obj_t dest[2];
        mp_load_method_maybe(uart, needed[i], dest);
        if (dest[0] == MP_OBJ_NULL) {
            mp_raise_msg_varg(&mp_type_TypeError,
                              MP_ERROR_TEXT("SerialBus(): uart must be a UART (write, read, any), not %s (it has "
                                            "no %q())"),
                              mp_obj_get_type_str(uart), needed[i]);
        }
    }
    return MP_OBJ_FROM_PTR(new_engine(type, uart, NULL, (uint32_t)vals[ARG_baud].u_int));
}

static ob_serial_bus_slot_t *slot_arg(serial_bus_obj_t *self, mp_obj_t obj, int *index) {
    mp_int_t slot = mp_obj_is_small_int(obj) ? MP_OBJ_SMALL_INT_VALUE(obj) : -1;
    ob_serial_bus_slot_t *found = slot >= 0 && slot < OB_SERIAL_BUS_MAX_SLOTS
                                      ? ob_serial_bus_slot(&self->bus, (int)slot)
                                      : NULL;
    if (found == NULL || mp_obj_is_bool(obj)) {
        mp_raise_msg_varg(&mp_type_ValueError, MP_ERROR_TEXT("slot %r is not an adopted servo on this bus engine"),
                          obj);
    }
    if (index != NULL) {
        *index = (int)slot;
    }
    return found;
}

static void set_subscribed(serial_bus_obj_t *self, bool on) {
    mp_obj_t dest[3];
    mp_load_method(ob_mp_motor_process_get(), on ? MP_QSTR_subscribe : MP_QSTR_unsubscribe, dest);
    dest[2] = MP_OBJ_FROM_PTR(self);
    mp_call_method_n_kw(1, 0, dest);
}

static mp_obj_t serial_bus_adopt(size_t n_args, const mp_obj_t *pos_args, mp_map_t *kw_args) {
    enum { ARG_servo_id, ARG_invert, ARG_counts_per_rev };
    static const mp_arg_t allowed[] = {
        {MP_QSTR_servo_id, MP_ARG_REQUIRED | MP_ARG_INT, {.u_int = 0}},
        {MP_QSTR_invert, MP_ARG_BOOL, {.u_bool = false}},
        {MP_QSTR_counts_per_rev, MP_ARG_INT, {.u_int = OB_SERIAL_BUS_COUNTS_PER_REV}},
    };
    mp_arg_val_t vals[MP_ARRAY_SIZE(allowed)];
    mp_arg_parse_all(n_args - 1, pos_args + 1, kw_args, MP_ARRAY_SIZE(allowed), allowed, vals);
    serial_bus_obj_t *self = MP_OBJ_TO_PTR(pos_args[0]);
    int servo_id = (int)vals[ARG_servo_id].u_int;
    if (vals[ARG_counts_per_rev].u_int != OB_SERIAL_BUS_COUNTS_PER_REV) {
        mp_raise_msg_varg(&mp_type_ValueError, MP_ERROR_TEXT("adopt(counts_per_rev=%d): %s"),
                          (int)vals[ARG_counts_per_rev].u_int, ob_serial_bus_strerror(OB_SERIAL_BUS_E_COUNTS));
    }
    int slot = -1;
    ob_serial_bus_error_t error = ob_serial_bus_adopt(&self->bus, servo_id, vals[ARG_invert].u_bool, &slot);
    ob_mp_subscriber_raise(&self->sub);
    switch (error) {
        case OB_SERIAL_BUS_OK:
            break;
        case OB_SERIAL_BUS_E_SILENT:
            mp_raise_msg_varg(&mp_type_OSError,
                              MP_ERROR_TEXT("motor is not responding on the bus: servo id %d did not answer when the "
                                            "bus engine adopted it. Check the servo's power and TX/RX wiring, and "
                                            "that it really has that bus id - `openbricks servo-id --scan` lists "
                                            "the ids actually answering on the bus."),
                              servo_id);
        case OB_SERIAL_BUS_E_ADOPTED:
            mp_raise_msg_varg(&mp_type_ValueError,
                              MP_ERROR_TEXT("adopt(%d): servo id %d is already adopted (slot %d); release() it first"),
                              servo_id, servo_id, slot);
        default:
            mp_raise_msg_varg(&mp_type_ValueError, MP_ERROR_TEXT("adopt(%d): %s"), servo_id,
                              ob_serial_bus_strerror(error));
    }
    set_subscribed(self, true); /* idempotent; motor_process may have been reset since */
    return MP_OBJ_NEW_SMALL_INT(slot);
}
static MP_DEFINE_CONST_FUN_OBJ_KW(serial_bus_adopt_obj, 2, serial_bus_adopt);

static mp_obj_t serial_bus_release(mp_obj_t self_in, mp_obj_t slot_in) {
    serial_bus_obj_t *self = MP_OBJ_TO_PTR(self_in);
    int index;
    slot_arg(self, slot_in, &index);
    (void)ob_serial_bus_release(&self->bus, index);
    ob_mp_subscriber_raise(&self->sub);
    if (!ob_serial_bus_active(&self->bus)) {
        set_subscribed(self, false);
    }
    return mp_const_none;
}
static MP_DEFINE_CONST_FUN_OBJ_2(serial_bus_release_obj, serial_bus_release);

static mp_obj_t serial_bus_motor_io(mp_obj_t self_in, mp_obj_t slot_in) {
    serial_bus_obj_t *self = MP_OBJ_TO_PTR(self_in);
    ob_serial_bus_slot_t *slot = slot_arg(self, slot_in, NULL);
    slot_io_obj_t *io = mp_obj_malloc(slot_io_obj_t, &slot_io_type);
    io->owner = self;
    io->base.io = ob_serial_bus_motor_io(slot);
    return MP_OBJ_FROM_PTR(io);
}
static MP_DEFINE_CONST_FUN_OBJ_2(serial_bus_motor_io_obj, serial_bus_motor_io);

static mp_obj_t serial_bus_angle_deg(mp_obj_t self_in, mp_obj_t slot_in) {
    ob_serial_bus_slot_t *slot = slot_arg(MP_OBJ_TO_PTR(self_in), slot_in, NULL);
    return ob_serial_bus_answering(slot) ? mp_obj_new_float(ob_serial_bus_angle_deg(slot)) : mp_const_none;
}
static MP_DEFINE_CONST_FUN_OBJ_2(serial_bus_angle_deg_obj, serial_bus_angle_deg);

static mp_obj_t serial_bus_speed_dps(mp_obj_t self_in, mp_obj_t slot_in) {
    ob_serial_bus_slot_t *slot = slot_arg(MP_OBJ_TO_PTR(self_in), slot_in, NULL);
    return ob_serial_bus_answering(slot) ? mp_obj_new_float(slot->speed_dps) : mp_const_none;
}
static MP_DEFINE_CONST_FUN_OBJ_2(serial_bus_speed_dps_obj, serial_bus_speed_dps);

static mp_obj_t serial_bus_load_pct(mp_obj_t self_in, mp_obj_t slot_in) {
    ob_serial_bus_slot_t *slot = slot_arg(MP_OBJ_TO_PTR(self_in), slot_in, NULL);
    return ob_serial_bus_answering(slot) ? mp_obj_new_float(slot->load_pct) : mp_const_none;
}
static MP_DEFINE_CONST_FUN_OBJ_2(serial_bus_load_pct_obj, serial_bus_load_pct);

static mp_obj_t serial_bus_stats(mp_obj_t self_in, mp_obj_t slot_in) {
    ob_serial_bus_slot_t *slot = slot_arg(MP_OBJ_TO_PTR(self_in), slot_in, NULL);
    mp_obj_t items[3] = {mp_obj_new_int_from_uint(slot->replies), mp_obj_new_int_from_uint(slot->failed_reads),
                         mp_obj_new_int_from_uint(slot->failed_in_a_row)};
    return mp_obj_new_tuple(3, items);
}
static MP_DEFINE_CONST_FUN_OBJ_2(serial_bus_stats_obj, serial_bus_stats);

static mp_obj_t serial_bus_bus_stats(mp_obj_t self_in) {
    serial_bus_obj_t *self = MP_OBJ_TO_PTR(self_in);
    mp_obj_t dict = mp_obj_new_dict(4);
    mp_obj_dict_store(dict, MP_OBJ_NEW_QSTR(MP_QSTR_ticks), mp_obj_new_int_from_uint(self->bus.ticks));
    mp_obj_dict_store(dict, MP_OBJ_NEW_QSTR(MP_QSTR_last_tick_bus_us),
                      mp_obj_new_int_from_uint(self->bus.last_tick_bus_us));
    mp_obj_dict_store(dict, MP_OBJ_NEW_QSTR(MP_QSTR_bus_us_total),
                      mp_obj_new_int_from_ull(self->bus.bus_us_total));
    mp_obj_dict_store(dict, MP_OBJ_NEW_QSTR(MP_QSTR_garbage_frames),
                      mp_obj_new_int_from_uint(self->bus.garbage_frames));
    return dict;
}
static MP_DEFINE_CONST_FUN_OBJ_1(serial_bus_bus_stats_obj, serial_bus_bus_stats);

static mp_obj_t serial_bus_tick(mp_obj_t self_in, mp_obj_t now_in) {
    serial_bus_obj_t *self = MP_OBJ_TO_PTR(self_in);
    ob_serial_bus_tick(&self->bus, ob_mp_time_ms(now_in, "SerialBus.tick"));
    ob_mp_subscriber_raise(&self->sub);
    return mp_const_none;
}
static MP_DEFINE_CONST_FUN_OBJ_2(serial_bus_tick_obj, serial_bus_tick);

/* ---- st_move_core: the slot's own moves and holds, and its flags ---- */

static mp_obj_t serial_bus_move(size_t n_args, const mp_obj_t *pos_args, mp_map_t *kw_args) {
    enum { ARG_self, ARG_slot, ARG_speed_dps, ARG_angle_deg, ARG_then, ARG_accel_dps2 };
    static const mp_arg_t allowed[] = {
        {MP_QSTR_self, MP_ARG_REQUIRED | MP_ARG_OBJ, {.u_obj = MP_OBJ_NULL}},
        {MP_QSTR_slot, MP_ARG_REQUIRED | MP_ARG_OBJ, {.u_obj = MP_OBJ_NULL}},
        {MP_QSTR_speed_dps, MP_ARG_REQUIRED | MP_ARG_OBJ, {.u_obj = MP_OBJ_NULL}},
        {MP_QSTR_angle_deg, MP_ARG_REQUIRED | MP_ARG_OBJ, {.u_obj = MP_OBJ_NULL}},
        {MP_QSTR_then, MP_ARG_OBJ, {.u_obj = MP_OBJ_NULL}},
        {MP_QSTR_accel_dps2, MP_ARG_OBJ, {.u_obj = mp_const_none}},
    };
    static const char *where = "SerialBus.move";
    mp_arg_val_t args[MP_ARRAY_SIZE(allowed)];
    mp_arg_parse_all(n_args, pos_args, kw_args, MP_ARRAY_SIZE(allowed), allowed, args);
    ob_serial_bus_slot_t *slot = slot_arg(MP_OBJ_TO_PTR(args[ARG_self].u_obj), args[ARG_slot].u_obj, NULL);
    float speed = ob_mp_float(args[ARG_speed_dps].u_obj, where, "speed_dps");
    float angle = ob_mp_float(args[ARG_angle_deg].u_obj, where, "angle_deg");
    ob_then_t then = args[ARG_then].u_obj != MP_OBJ_NULL ? ob_mp_then(args[ARG_then].u_obj, where) : OB_THEN_HOLD;
    float accel = ob_mp_given(args[ARG_accel_dps2].u_obj)
                      ? ob_mp_positive_float(args[ARG_accel_dps2].u_obj, where, "accel_dps2")
                      : 0.0f;
    if (speed == 0.0f) {
        mp_raise_msg_varg(&mp_type_ValueError, MP_ERROR_TEXT("%s: speed_dps must not be 0 (use hold() to stay in place)"),
                          where);
    }
    ob_serial_bus_move(slot, speed, angle, then, accel);
    return mp_const_none;
}
static MP_DEFINE_CONST_FUN_OBJ_KW(serial_bus_move_obj, 4, serial_bus_move);

static mp_obj_t serial_bus_hold(mp_obj_t self_in, mp_obj_t slot_in) {
    ob_serial_bus_hold(slot_arg(MP_OBJ_TO_PTR(self_in), slot_in, NULL));
    return mp_const_none;
}
static MP_DEFINE_CONST_FUN_OBJ_2(serial_bus_hold_obj, serial_bus_hold);

static mp_obj_t serial_bus_end_move(mp_obj_t self_in, mp_obj_t slot_in) {
    ob_serial_bus_end_move(slot_arg(MP_OBJ_TO_PTR(self_in), slot_in, NULL));
    return mp_const_none;
}
static MP_DEFINE_CONST_FUN_OBJ_2(serial_bus_end_move_obj, serial_bus_end_move);

static mp_obj_t serial_bus_done(mp_obj_t self_in, mp_obj_t slot_in) {
    serial_bus_obj_t *self = MP_OBJ_TO_PTR(self_in);
    int index;
    ob_serial_bus_slot_t *slot = slot_arg(self, slot_in, &index);
    if (ob_serial_bus_move_lost_feedback(slot)) {
        mp_raise_msg_varg(&mp_type_OSError,
                          MP_ERROR_TEXT("SerialBus.done(%d): servo id %d stopped answering mid-move; the move was "
                                        "halted"),
                          index, (int)slot->servo_id);
    }
    return mp_obj_new_bool(ob_serial_bus_arrived(slot));
}
static MP_DEFINE_CONST_FUN_OBJ_2(serial_bus_done_obj, serial_bus_done);

static mp_obj_t serial_bus_stalled(size_t n_args, const mp_obj_t *pos_args, mp_map_t *kw_args) {
    enum { ARG_self, ARG_slot, ARG_load_pct, ARG_speed_dps };
    static const mp_arg_t allowed[] = {
        {MP_QSTR_self, MP_ARG_REQUIRED | MP_ARG_OBJ, {.u_obj = MP_OBJ_NULL}},
        {MP_QSTR_slot, MP_ARG_REQUIRED | MP_ARG_OBJ, {.u_obj = MP_OBJ_NULL}},
        {MP_QSTR_load_pct, MP_ARG_OBJ, {.u_obj = mp_const_none}},
        {MP_QSTR_speed_dps, MP_ARG_OBJ, {.u_obj = mp_const_none}},
    };
    static const char *where = "SerialBus.stalled";
    mp_arg_val_t args[MP_ARRAY_SIZE(allowed)];
    mp_arg_parse_all(n_args, pos_args, kw_args, MP_ARRAY_SIZE(allowed), allowed, args);
    ob_serial_bus_slot_t *slot = slot_arg(MP_OBJ_TO_PTR(args[ARG_self].u_obj), args[ARG_slot].u_obj, NULL);
    float load = ob_mp_given(args[ARG_load_pct].u_obj) ? ob_mp_positive_float(args[ARG_load_pct].u_obj, where, "load_pct")
                                                       : OB_SERIAL_BUS_STALL_LOAD_PCT;
    float speed = ob_mp_given(args[ARG_speed_dps].u_obj) ? ob_mp_float(args[ARG_speed_dps].u_obj, where, "speed_dps")
                                                         : OB_SERIAL_BUS_STALL_SPEED_DPS;
    return mp_obj_new_bool(ob_serial_bus_stalled(slot, load, speed));
}
static MP_DEFINE_CONST_FUN_OBJ_KW(serial_bus_stalled_obj, 2, serial_bus_stalled);

static mp_obj_t serial_bus_set_drive(size_t n_args, const mp_obj_t *pos_args, mp_map_t *kw_args) {
    enum { ARG_self, ARG_slot, ARG_drive, ARG_max_dps };
    static const mp_arg_t allowed[] = {
        {MP_QSTR_self, MP_ARG_REQUIRED | MP_ARG_OBJ, {.u_obj = MP_OBJ_NULL}},
        {MP_QSTR_slot, MP_ARG_REQUIRED | MP_ARG_OBJ, {.u_obj = MP_OBJ_NULL}},
        {MP_QSTR_drive, MP_ARG_REQUIRED | MP_ARG_OBJ, {.u_obj = MP_OBJ_NULL}},
        {MP_QSTR_max_dps, MP_ARG_OBJ, {.u_obj = mp_const_none}},
    };
    static const char *where = "SerialBus.set_drive";
    mp_arg_val_t args[MP_ARRAY_SIZE(allowed)];
    mp_arg_parse_all(n_args, pos_args, kw_args, MP_ARRAY_SIZE(allowed), allowed, args);
    serial_bus_obj_t *self = MP_OBJ_TO_PTR(args[ARG_self].u_obj);
    int index;
    ob_serial_bus_slot_t *slot = slot_arg(self, args[ARG_slot].u_obj, &index);
    mp_obj_t drive = args[ARG_drive].u_obj;
    bool wheel = mp_obj_is_str(drive) && strcmp(mp_obj_str_get_str(drive), "wheel") == 0;
    if (!wheel && !(mp_obj_is_str(drive) && strcmp(mp_obj_str_get_str(drive), "duty") == 0)) {
        mp_raise_msg_varg(&mp_type_ValueError,
                          MP_ERROR_TEXT("%s(drive=%r): give \"duty\" (the engine closes the loop over raw duty) or "
                                        "\"wheel\" (the servo's own speed controller)"),
                          where, drive);
    }
    float max_dps = wheel ? ob_mp_positive_float(args[ARG_max_dps].u_obj, where, "max_dps") : 0.0f;
    ob_serial_bus_error_t error = ob_serial_bus_set_drive(&self->bus, index, wheel, max_dps);
    ob_mp_subscriber_raise(&self->sub);
    if (error != OB_SERIAL_BUS_OK) {
        mp_raise_msg_varg(&mp_type_OSError, MP_ERROR_TEXT("%s: servo id %d is %s"), where, (int)slot->servo_id,
                          ob_serial_bus_strerror(error));
    }
    return mp_const_none;
}
static MP_DEFINE_CONST_FUN_OBJ_KW(serial_bus_set_drive_obj, 3, serial_bus_set_drive);

static const mp_rom_map_elem_t serial_bus_locals_table[] = {
    {MP_ROM_QSTR(MP_QSTR_set_drive), MP_ROM_PTR(&serial_bus_set_drive_obj)},
    {MP_ROM_QSTR(MP_QSTR_move), MP_ROM_PTR(&serial_bus_move_obj)},
    {MP_ROM_QSTR(MP_QSTR_hold), MP_ROM_PTR(&serial_bus_hold_obj)},
    {MP_ROM_QSTR(MP_QSTR_end_move), MP_ROM_PTR(&serial_bus_end_move_obj)},
    {MP_ROM_QSTR(MP_QSTR_done), MP_ROM_PTR(&serial_bus_done_obj)},
    {MP_ROM_QSTR(MP_QSTR_stalled), MP_ROM_PTR(&serial_bus_stalled_obj)},
    {MP_ROM_QSTR(MP_QSTR_adopt), MP_ROM_PTR(&serial_bus_adopt_obj)},
    {MP_ROM_QSTR(MP_QSTR_release), MP_ROM_PTR(&serial_bus_release_obj)},
    {MP_ROM_QSTR(MP_QSTR_motor_io), MP_ROM_PTR(&serial_bus_motor_io_obj)},
    {MP_ROM_QSTR(MP_QSTR_angle_deg), MP_ROM_PTR(&serial_bus_angle_deg_obj)},
    {MP_ROM_QSTR(MP_QSTR_speed_dps), MP_ROM_PTR(&serial_bus_speed_dps_obj)},
    {MP_ROM_QSTR(MP_QSTR_load_pct), MP_ROM_PTR(&serial_bus_load_pct_obj)},
    {MP_ROM_QSTR(MP_QSTR_stats), MP_ROM_PTR(&serial_bus_stats_obj)},
    {MP_ROM_QSTR(MP_QSTR_bus_stats), MP_ROM_PTR(&serial_bus_bus_stats_obj)},
    {MP_ROM_QSTR(MP_QSTR_tick), MP_ROM_PTR(&serial_bus_tick_obj)},
};
static MP_DEFINE_CONST_DICT(serial_bus_locals, serial_bus_locals_table);

static void serial_bus_attr(mp_obj_t self_in, qstr attr, mp_obj_t *dest) {
    ob_mp_locked_attr(self_in, attr, dest, &serial_bus_locals);
}

MP_DEFINE_CONST_OBJ_TYPE(
    ob_mp_serial_bus_type,
    MP_QSTR_SerialBus,
    MP_TYPE_FLAG_NONE,
    make_new, serial_bus_make_new,
    attr, serial_bus_attr,
    locals_dict, &serial_bus_locals,
    parent, &ob_mp_subscriber_type
    );

/* ---- A slot's motor IO ---- */

static mp_obj_t slot_io_read_angle(mp_obj_t self_in) {
    slot_io_obj_t *self = MP_OBJ_TO_PTR(self_in);
    float angle;
    return self->base.io.read_angle(self->base.io.ctx, &angle) ? mp_obj_new_float(angle) : mp_const_none;
}
static MP_DEFINE_CONST_FUN_OBJ_1(slot_io_read_angle_obj, slot_io_read_angle);

static mp_obj_t slot_io_write_duty(mp_obj_t self_in, mp_obj_t duty_in) {
    slot_io_obj_t *self = MP_OBJ_TO_PTR(self_in);
    self->base.io.write_duty(self->base.io.ctx, ob_mp_float(duty_in, "write_duty", "duty_pct"));
    return mp_const_none;
}
static MP_DEFINE_CONST_FUN_OBJ_2(slot_io_write_duty_obj, slot_io_write_duty);

static mp_obj_t slot_io_coast(mp_obj_t self_in) {
    slot_io_obj_t *self = MP_OBJ_TO_PTR(self_in);
    self->base.io.write_coast(self->base.io.ctx);
    return mp_const_none;
}
static MP_DEFINE_CONST_FUN_OBJ_1(slot_io_coast_obj, slot_io_coast);

static const mp_rom_map_elem_t slot_io_locals_table[] = {
    {MP_ROM_QSTR(MP_QSTR_read_angle), MP_ROM_PTR(&slot_io_read_angle_obj)},
    {MP_ROM_QSTR(MP_QSTR_write_duty), MP_ROM_PTR(&slot_io_write_duty_obj)},
    {MP_ROM_QSTR(MP_QSTR_coast), MP_ROM_PTR(&slot_io_coast_obj)},
};
static MP_DEFINE_CONST_DICT(slot_io_locals, slot_io_locals_table);

static void slot_io_attr(mp_obj_t self_in, qstr attr, mp_obj_t *dest) {
    ob_mp_locked_attr(self_in, attr, dest, &slot_io_locals);
}

static MP_DEFINE_CONST_OBJ_TYPE(
    slot_io_type,
    MP_QSTR_SerialBusSlotIO,
    MP_TYPE_FLAG_NONE,
    attr, slot_io_attr,
    locals_dict, &slot_io_locals,
    parent, &ob_mp_motor_io_type
    );

/* ---- serial_bus(uart_id, ...) ---- */

static mp_obj_t mod_serial_bus(size_t n_args, const mp_obj_t *pos_args, mp_map_t *kw_args) {
    enum { ARG_uart_id, ARG_tx, ARG_rx, ARG_baud, ARG_dir_pin };
    static const mp_arg_t allowed[] = {
        {MP_QSTR_uart_id, MP_ARG_REQUIRED | MP_ARG_INT, {.u_int = 0}},
        {MP_QSTR_tx, MP_ARG_OBJ, {.u_obj = mp_const_none}},
        {MP_QSTR_rx, MP_ARG_OBJ, {.u_obj = mp_const_none}},
        {MP_QSTR_baud, MP_ARG_INT, {.u_int = OB_SERIAL_BUS_DEFAULT_BAUD}},
        {MP_QSTR_dir_pin, MP_ARG_OBJ, {.u_obj = mp_const_none}},
    };
    mp_arg_val_t vals[MP_ARRAY_SIZE(allowed)];
    mp_arg_parse_all(n_args, pos_args, kw_args, MP_ARRAY_SIZE(allowed), allowed, vals);
    uint32_t baud = (uint32_t)vals[ARG_baud].u_int;
    #if defined(ESP_PLATFORM)
    const ob_uart_t *native = ob_mp_uart_esp32_open((int)vals[ARG_uart_id].u_int, vals[ARG_tx].u_obj,
                                                    vals[ARG_rx].u_obj, baud, vals[ARG_dir_pin].u_obj);
    return MP_OBJ_FROM_PTR(new_engine(&ob_mp_serial_bus_type, mp_const_none, native, baud));
    #else
    /* The host's UARTs (the tests' fake board) have no direction pin to drive. */
    mp_obj_t machine = mp_import_name(MP_QSTR_machine, mp_const_none, MP_OBJ_NEW_SMALL_INT(0));
    mp_obj_t uart_type = mp_load_attr(machine, MP_QSTR_UART);
    mp_obj_t call_args[1 + 2 * 4] = {
        MP_OBJ_NEW_SMALL_INT(vals[ARG_uart_id].u_int),
        MP_OBJ_NEW_QSTR(MP_QSTR_baudrate), mp_obj_new_int_from_uint(baud),
        MP_OBJ_NEW_QSTR(MP_QSTR_tx), vals[ARG_tx].u_obj,
        MP_OBJ_NEW_QSTR(MP_QSTR_rx), vals[ARG_rx].u_obj,
        MP_OBJ_NEW_QSTR(MP_QSTR_timeout), MP_OBJ_NEW_SMALL_INT(0),
    };
    mp_obj_t uart = mp_call_function_n_kw(uart_type, 1, 4, call_args);
    return MP_OBJ_FROM_PTR(new_engine(&ob_mp_serial_bus_type, uart, ob_mp_native_uart_get(uart), baud));
    #endif
}
MP_DEFINE_CONST_FUN_OBJ_KW(ob_mp_serial_bus_obj, 1, mod_serial_bus);
