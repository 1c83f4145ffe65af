/*
 * _openbricks_native.scs: the serial-bus packet codec (host: py_scs.c).
 *
 * Packet builders return bytes; parsers take any buffer. Bad arguments raise
 * ValueError naming the argument and its range; bus data never raises, it
 * decodes to a result string. Parsed frames are attribute tuples with the host's
 * field names (result, consumed, needed, id, instruction / error, params).
 */
#include <string.h>

#include "py/objtuple.h"

#include "mp_bindings.h"
#include "scs.h"

static uint8_t byte_arg(mp_obj_t obj, const char *what, mp_int_t lo, mp_int_t hi) {
    if (obj == mp_const_true || obj == mp_const_false || !mp_obj_is_int(obj)) {
        mp_raise_msg_varg(&mp_type_TypeError, MP_ERROR_TEXT("%s must be an int, not %s"), what, mp_obj_get_type_str(obj));
    }
    if (!mp_obj_is_small_int(obj) || mp_obj_get_int(obj) < lo || mp_obj_get_int(obj) > hi) {
        mp_raise_msg_varg(&mp_type_ValueError, MP_ERROR_TEXT("%s is out of range %d..%d"), what, (int)lo, (int)hi);
    }
    return (uint8_t)mp_obj_get_int(obj);
}

static mp_obj_t packet(const uint8_t *buf, int n, const char *what) {
    if (n < 0) {
        mp_raise_msg_varg(&mp_type_ValueError, MP_ERROR_TEXT("%s: %s"), what, ob_scs_strerror(n));
    }
    return mp_obj_new_bytes(buf, (size_t)n);
}

static MP_NORETURN void span_error(const char *what, size_t n, uint8_t reg) {
    mp_raise_msg_varg(&mp_type_ValueError, MP_ERROR_TEXT("%s of %u bytes at register 0x%02x runs past register 0xFF"),
                      what, (unsigned)n, (unsigned)reg);
}

static mp_obj_t scs_ping(size_t n_args, const mp_obj_t *pos_args, mp_map_t *kw_args) {
    static const mp_arg_t allowed[] = {
        {MP_QSTR_id, MP_ARG_REQUIRED | MP_ARG_OBJ, {.u_obj = MP_OBJ_NULL}},
    };
    mp_arg_val_t args[MP_ARRAY_SIZE(allowed)];
    mp_arg_parse_all(n_args, pos_args, kw_args, MP_ARRAY_SIZE(allowed), allowed, args);
    uint8_t out[OB_SCS_MAX_FRAME];
    uint8_t id = byte_arg(args[0].u_obj, "servo id", 0, OB_SCS_BROADCAST_ID);
    return packet(out, ob_scs_encode_ping(id, out, sizeof out), "ping");
}
static MP_DEFINE_CONST_FUN_OBJ_KW(scs_ping_obj, 0, scs_ping);

static mp_obj_t scs_read(size_t n_args, const mp_obj_t *pos_args, mp_map_t *kw_args) {
    static const mp_arg_t allowed[] = {
        {MP_QSTR_id, MP_ARG_REQUIRED | MP_ARG_OBJ, {.u_obj = MP_OBJ_NULL}},
        {MP_QSTR_register, MP_ARG_REQUIRED | MP_ARG_OBJ, {.u_obj = MP_OBJ_NULL}},
        {MP_QSTR_length, MP_ARG_REQUIRED | MP_ARG_OBJ, {.u_obj = MP_OBJ_NULL}},
    };
    mp_arg_val_t args[MP_ARRAY_SIZE(allowed)];
    mp_arg_parse_all(n_args, pos_args, kw_args, MP_ARRAY_SIZE(allowed), allowed, args);
    uint8_t id = byte_arg(args[0].u_obj, "servo id (a read needs one servo, not broadcast)", 0, OB_SCS_MAX_SERVO_ID);
    uint8_t reg = byte_arg(args[1].u_obj, "register", 0, 0xFF);
    uint8_t len = byte_arg(args[2].u_obj, "read length", 1, OB_SCS_MAX_PARAMS);
    uint8_t out[OB_SCS_MAX_FRAME];
    int n = ob_scs_encode_read(id, reg, len, out, sizeof out);
    if (n == OB_SCS_E_REGISTER) {
        span_error("read", len, reg);
    }
    return packet(out, n, "read");
}
static MP_DEFINE_CONST_FUN_OBJ_KW(scs_read_obj, 0, scs_read);

static mp_obj_t scs_write(size_t n_args, const mp_obj_t *pos_args, mp_map_t *kw_args) {
    static const mp_arg_t allowed[] = {
        {MP_QSTR_id, MP_ARG_REQUIRED | MP_ARG_OBJ, {.u_obj = MP_OBJ_NULL}},
        {MP_QSTR_register, MP_ARG_REQUIRED | MP_ARG_OBJ, {.u_obj = MP_OBJ_NULL}},
        {MP_QSTR_data, MP_ARG_REQUIRED | MP_ARG_OBJ, {.u_obj = MP_OBJ_NULL}},
    };
    mp_arg_val_t args[MP_ARRAY_SIZE(allowed)];
    mp_arg_parse_all(n_args, pos_args, kw_args, MP_ARRAY_SIZE(allowed), allowed, args);
    uint8_t id = byte_arg(args[0].u_obj, "servo id", 0, OB_SCS_BROADCAST_ID);
    uint8_t reg = byte_arg(args[1].u_obj, "register", 0, 0xFF);
    mp_buffer_info_t data;
    mp_get_buffer_raise(args[2].u_obj, &data, MP_BUFFER_READ);
    if (data.len < 1 || data.len > OB_SCS_MAX_PARAMS - 1u) {
        mp_raise_msg_varg(&mp_type_ValueError, MP_ERROR_TEXT("write data is %u bytes; it must be 1..%u"),
                          (unsigned)data.len, OB_SCS_MAX_PARAMS - 1u);
    }
    uint8_t out[OB_SCS_MAX_FRAME];
    int n = ob_scs_encode_write(id, reg, data.buf, data.len, out, sizeof out);
    if (n == OB_SCS_E_REGISTER) {
        span_error("write", data.len, reg);
    }
    return packet(out, n, "write");
}
static MP_DEFINE_CONST_FUN_OBJ_KW(scs_write_obj, 0, scs_write);

static mp_obj_t scs_sync_write(size_t n_args, const mp_obj_t *pos_args, mp_map_t *kw_args) {
    static const mp_arg_t allowed[] = {
        {MP_QSTR_register, MP_ARG_REQUIRED | MP_ARG_OBJ, {.u_obj = MP_OBJ_NULL}},
        {MP_QSTR_rows, MP_ARG_REQUIRED | MP_ARG_OBJ, {.u_obj = MP_OBJ_NULL}},
    };
    mp_arg_val_t args[MP_ARRAY_SIZE(allowed)];
    mp_arg_parse_all(n_args, pos_args, kw_args, MP_ARRAY_SIZE(allowed), allowed, args);
    uint8_t reg = byte_arg(args[0].u_obj, "register", 0, 0xFF);
    size_t n_rows;
    mp_obj_t *rows;
    mp_obj_get_array(args[1].u_obj, &n_rows, &rows);
    if (n_rows < 1 || n_rows > (OB_SCS_MAX_PARAMS - 2u) / 2u) {
        mp_raise_msg_varg(&mp_type_ValueError, MP_ERROR_TEXT("sync_write has %u rows; it takes 1..%u servos"),
                          (unsigned)n_rows, (OB_SCS_MAX_PARAMS - 2u) / 2u);
    }
    uint8_t ids[OB_SCS_MAX_PARAMS];
    uint8_t data[OB_SCS_MAX_PARAMS];
    uint8_t data_len = 0;
    size_t used = 0;
    for (size_t i = 0; i < n_rows; i++) {
        size_t n_fields;
        mp_obj_t *fields;
        if (!mp_obj_is_type(rows[i], &mp_type_tuple)) {
            mp_raise_msg_varg(&mp_type_TypeError, MP_ERROR_TEXT("sync_write row %u must be an (id, data) pair, not %s"),
                              (unsigned)i, mp_obj_get_type_str(rows[i]));
        }
        mp_obj_tuple_get(rows[i], &n_fields, &fields);
        if (n_fields != 2) {
            mp_raise_msg_varg(&mp_type_TypeError, MP_ERROR_TEXT("sync_write row %u must be an (id, data) pair"),
                              (unsigned)i);
        }
        ids[i] = byte_arg(fields[0], "sync_write servo id", 0, OB_SCS_MAX_SERVO_ID);
        mp_buffer_info_t view;
        mp_get_buffer_raise(fields[1], &view, MP_BUFFER_READ);
        if (i == 0) {
            if (view.len < 1 || view.len > 0xFF) {
                mp_raise_msg_varg(&mp_type_ValueError, MP_ERROR_TEXT("sync_write data for servo %u is %u bytes; it must be 1..255"),
                                  (unsigned)ids[i], (unsigned)view.len);
            }
            data_len = (uint8_t)view.len;
        } else if (view.len != data_len) {
            mp_raise_msg_varg(&mp_type_ValueError,
                              MP_ERROR_TEXT("sync_write data for servo %u is %u bytes but the first row has %u; every "
                                            "servo gets the same register span"),
                              (unsigned)ids[i], (unsigned)view.len, (unsigned)data_len);
        }
        if (used + view.len > OB_SCS_MAX_PARAMS) {
            mp_raise_msg_varg(&mp_type_ValueError, MP_ERROR_TEXT("sync_write rows exceed the %u parameter bytes of one packet"),
                              OB_SCS_MAX_PARAMS);
        }
        memcpy(data + used, view.buf, view.len);
        used += view.len;
    }
    uint8_t out[OB_SCS_MAX_FRAME];
    int n = ob_scs_encode_sync_write(reg, data_len, ids, data, n_rows, out, sizeof out);
    if (n == OB_SCS_E_LENGTH) {
        mp_raise_msg_varg(&mp_type_ValueError,
                          MP_ERROR_TEXT("sync_write of %u servos x %u bytes exceeds the %u parameter bytes of one packet"),
                          (unsigned)n_rows, (unsigned)data_len, OB_SCS_MAX_PARAMS);
    }
    if (n == OB_SCS_E_REGISTER) {
        span_error("sync_write", data_len, reg);
    }
    return packet(out, n, "sync_write");
}
static MP_DEFINE_CONST_FUN_OBJ_KW(scs_sync_write_obj, 0, scs_sync_write);

/* status() and frame(): an id, a code byte and optional params. */
static mp_obj_t params_packet(size_t n_args, const mp_obj_t *pos_args, mp_map_t *kw_args, bool is_status) {
    const mp_arg_t allowed[] = {
        {MP_QSTR_id, MP_ARG_REQUIRED | MP_ARG_OBJ, {.u_obj = MP_OBJ_NULL}},
        {is_status ? MP_QSTR_error : MP_QSTR_instruction, (is_status ? 0 : MP_ARG_REQUIRED) | MP_ARG_OBJ,
         {.u_obj = MP_OBJ_NULL}},
        {MP_QSTR_params, MP_ARG_OBJ, {.u_obj = MP_OBJ_NULL}},
    };
    mp_arg_val_t args[MP_ARRAY_SIZE(allowed)];
    mp_arg_parse_all(n_args, pos_args, kw_args, MP_ARRAY_SIZE(allowed), allowed, args);
    const char *name = is_status ? "status" : "frame";
    uint8_t id = is_status ? byte_arg(args[0].u_obj, "servo id (a reply comes from one servo)", 0, OB_SCS_MAX_SERVO_ID)
                           : byte_arg(args[0].u_obj, "servo id", 0, OB_SCS_BROADCAST_ID);
    uint8_t code = 0;
    if (args[1].u_obj != MP_OBJ_NULL) {
        code = byte_arg(args[1].u_obj, is_status ? "error flags" : "instruction", 0, 0xFF);
    }
    mp_buffer_info_t params = {.buf = NULL, .len = 0};
    if (args[2].u_obj != MP_OBJ_NULL) {
        mp_get_buffer_raise(args[2].u_obj, &params, MP_BUFFER_READ);
    }
    if (params.len > OB_SCS_MAX_PARAMS) {
        mp_raise_msg_varg(&mp_type_ValueError, MP_ERROR_TEXT("%s params are %u bytes; a packet holds at most %u"), name,
                          (unsigned)params.len, OB_SCS_MAX_PARAMS);
    }
    uint8_t out[OB_SCS_MAX_FRAME];
    int n = is_status ? ob_scs_encode_status(id, code, params.buf, params.len, out, sizeof out)
                      : ob_scs_encode_frame(id, code, params.buf, params.len, out, sizeof out);
    return packet(out, n, name);
}

static mp_obj_t scs_status(size_t n_args, const mp_obj_t *pos_args, mp_map_t *kw_args) {
    return params_packet(n_args, pos_args, kw_args, true);
}
static MP_DEFINE_CONST_FUN_OBJ_KW(scs_status_obj, 0, scs_status);

static mp_obj_t scs_frame(size_t n_args, const mp_obj_t *pos_args, mp_map_t *kw_args) {
    return params_packet(n_args, pos_args, kw_args, false);
}
static MP_DEFINE_CONST_FUN_OBJ_KW(scs_frame_obj, 0, scs_frame);

static const qstr frame_fields[] = {MP_QSTR_result, MP_QSTR_consumed, MP_QSTR_needed, MP_QSTR_id, MP_QSTR_instruction,
                                    MP_QSTR_params};
static const qstr status_fields[] = {MP_QSTR_result, MP_QSTR_consumed, MP_QSTR_needed, MP_QSTR_id, MP_QSTR_error,
                                     MP_QSTR_params};

static qstr result_name(ob_scs_parse_t r) {
    switch (r) {
        case OB_SCS_PARSE_OK:
            return MP_QSTR_ok;
        case OB_SCS_PARSE_NEED_MORE:
            return MP_QSTR_need_more;
        case OB_SCS_PARSE_BAD_CHECKSUM:
            return MP_QSTR_bad_checksum;
        case OB_SCS_PARSE_BAD_HEADER:
            return MP_QSTR_bad_header;
        case OB_SCS_PARSE_BAD_LENGTH:
            return MP_QSTR_bad_length;
        default:
            return MP_QSTR_bad_argument;
    }
}

static mp_obj_t decode(mp_obj_t data_in, bool status) {
    mp_buffer_info_t data;
    mp_get_buffer_raise(data_in, &data, MP_BUFFER_READ);
    ob_scs_frame_t f;
    ob_scs_parse_t r = status ? ob_scs_parse_status(data.buf, data.len, &f) : ob_scs_parse_frame(data.buf, data.len, &f);
    mp_obj_t items[6] = {
        MP_OBJ_NEW_QSTR(result_name(r)),
        mp_obj_new_int_from_uint(f.consumed),
        mp_obj_new_int_from_uint(f.needed),
        MP_OBJ_NEW_SMALL_INT(f.id),
        MP_OBJ_NEW_SMALL_INT(f.code),
        /* Copied out: the caller's receive buffer may be reused for the next read. */
        mp_obj_new_bytes(f.param_len ? f.params : (const uint8_t *)"", f.param_len),
    };
    return mp_obj_new_attrtuple(status ? status_fields : frame_fields, 6, items);
}

static mp_obj_t scs_decode_frame(mp_obj_t data_in) {
    return decode(data_in, false);
}
static MP_DEFINE_CONST_FUN_OBJ_1(scs_decode_frame_obj, scs_decode_frame);

static mp_obj_t scs_decode_status(mp_obj_t data_in) {
    return decode(data_in, true);
}
static MP_DEFINE_CONST_FUN_OBJ_1(scs_decode_status_obj, scs_decode_status);

static mp_obj_t scs_checksum(mp_obj_t data_in) {
    mp_buffer_info_t data;
    mp_get_buffer_raise(data_in, &data, MP_BUFFER_READ);
    return MP_OBJ_NEW_SMALL_INT(ob_scs_checksum(data.buf, data.len));
}
static MP_DEFINE_CONST_FUN_OBJ_1(scs_checksum_obj, scs_checksum);

static mp_obj_t scs_flag_names(mp_obj_t flags_in) {
    uint8_t flags = byte_arg(flags_in, "error flags", 0, 0xFF);
    mp_obj_t names[8];
    size_t n = 0;
    for (unsigned bit = 0; bit < 8; bit++) {
        if (!(flags & (1u << bit))) {
            continue;
        }
        const char *name = ob_scs_flag_name(bit);
        if (name != NULL) {
            names[n++] = mp_obj_new_str(name, strlen(name));
        } else {
            char text[8] = "bit0";
            text[3] = (char)('0' + bit);
            names[n++] = mp_obj_new_str(text, 4);
        }
    }
    return mp_obj_new_tuple(n, names);
}
static MP_DEFINE_CONST_FUN_OBJ_1(scs_flag_names_obj, scs_flag_names);

/* Sign-magnitude register values: ints in, two little-endian register bytes out, and back. */
static mp_obj_t sm_encode(mp_obj_t value_in, unsigned sign_bit) {
    mp_int_t limit = ((mp_int_t)1 << sign_bit) - 1;
    if (value_in == mp_const_true || value_in == mp_const_false || !mp_obj_is_small_int(value_in) ||
        mp_obj_get_int(value_in) < -limit || mp_obj_get_int(value_in) > limit) {
        /* Saturating would silently command a different setpoint than the caller computed. */
        mp_raise_msg_varg(&mp_type_ValueError, MP_ERROR_TEXT("value does not fit a %u-bit sign-magnitude register (-%d..%d)"),
                          sign_bit + 1u, (int)limit, (int)limit);
    }
    uint8_t out[2];
    ob_scs_put_u16(out, ob_scs_sm_encode((int32_t)mp_obj_get_int(value_in), sign_bit));
    return mp_obj_new_bytes(out, 2);
}

static mp_obj_t sm_decode(mp_obj_t data_in, unsigned sign_bit) {
    mp_buffer_info_t data;
    mp_get_buffer_raise(data_in, &data, MP_BUFFER_READ);
    if (data.len != 2) {
        mp_raise_msg_varg(&mp_type_ValueError, MP_ERROR_TEXT("a 16-bit register value is 2 bytes, got %u"),
                          (unsigned)data.len);
    }
    return mp_obj_new_int(ob_scs_sm_decode(ob_scs_get_u16(data.buf), sign_bit));
}

static mp_obj_t scs_encode_speed(mp_obj_t v) {
    return sm_encode(v, OB_SCS_SPEED_SIGN_BIT);
}
static MP_DEFINE_CONST_FUN_OBJ_1(scs_encode_speed_obj, scs_encode_speed);

static mp_obj_t scs_decode_speed(mp_obj_t d) {
    return sm_decode(d, OB_SCS_SPEED_SIGN_BIT);
}
static MP_DEFINE_CONST_FUN_OBJ_1(scs_decode_speed_obj, scs_decode_speed);

static mp_obj_t scs_encode_position(mp_obj_t v) {
    return sm_encode(v, OB_SCS_POSITION_SIGN_BIT);
}
static MP_DEFINE_CONST_FUN_OBJ_1(scs_encode_position_obj, scs_encode_position);

static mp_obj_t scs_decode_position(mp_obj_t d) {
    return sm_decode(d, OB_SCS_POSITION_SIGN_BIT);
}
static MP_DEFINE_CONST_FUN_OBJ_1(scs_decode_position_obj, scs_decode_position);

static mp_obj_t scs_encode_load(mp_obj_t v) {
    return sm_encode(v, OB_SCS_LOAD_SIGN_BIT);
}
static MP_DEFINE_CONST_FUN_OBJ_1(scs_encode_load_obj, scs_encode_load);

static mp_obj_t scs_decode_load(mp_obj_t d) {
    return sm_decode(d, OB_SCS_LOAD_SIGN_BIT);
}
static MP_DEFINE_CONST_FUN_OBJ_1(scs_decode_load_obj, scs_decode_load);

static const mp_rom_map_elem_t scs_globals_table[] = {
    {MP_ROM_QSTR(MP_QSTR___name__), MP_ROM_QSTR(MP_QSTR_scs)},
    {MP_ROM_QSTR(MP_QSTR_ping), MP_ROM_PTR(&scs_ping_obj)},
    {MP_ROM_QSTR(MP_QSTR_read), MP_ROM_PTR(&scs_read_obj)},
    {MP_ROM_QSTR(MP_QSTR_write), MP_ROM_PTR(&scs_write_obj)},
    {MP_ROM_QSTR(MP_QSTR_sync_write), MP_ROM_PTR(&scs_sync_write_obj)},
    {MP_ROM_QSTR(MP_QSTR_status), MP_ROM_PTR(&scs_status_obj)},
    {MP_ROM_QSTR(MP_QSTR_frame), MP_ROM_PTR(&scs_frame_obj)},
    {MP_ROM_QSTR(MP_QSTR_decode_frame), MP_ROM_PTR(&scs_decode_frame_obj)},
    {MP_ROM_QSTR(MP_QSTR_decode_status), MP_ROM_PTR(&scs_decode_status_obj)},
    {MP_ROM_QSTR(MP_QSTR_checksum), MP_ROM_PTR(&scs_checksum_obj)},
    {MP_ROM_QSTR(MP_QSTR_flag_names), MP_ROM_PTR(&scs_flag_names_obj)},
    {MP_ROM_QSTR(MP_QSTR_encode_speed), MP_ROM_PTR(&scs_encode_speed_obj)},
    {MP_ROM_QSTR(MP_QSTR_decode_speed), MP_ROM_PTR(&scs_decode_speed_obj)},
    {MP_ROM_QSTR(MP_QSTR_encode_position), MP_ROM_PTR(&scs_encode_position_obj)},
    {MP_ROM_QSTR(MP_QSTR_decode_position), MP_ROM_PTR(&scs_decode_position_obj)},
    {MP_ROM_QSTR(MP_QSTR_encode_load), MP_ROM_PTR(&scs_encode_load_obj)},
    {MP_ROM_QSTR(MP_QSTR_decode_load), MP_ROM_PTR(&scs_decode_load_obj)},
    {MP_ROM_QSTR(MP_QSTR_BROADCAST_ID), MP_ROM_INT(OB_SCS_BROADCAST_ID)},
    {MP_ROM_QSTR(MP_QSTR_MAX_SERVO_ID), MP_ROM_INT(OB_SCS_MAX_SERVO_ID)},
    {MP_ROM_QSTR(MP_QSTR_PING), MP_ROM_INT(OB_SCS_INSTR_PING)},
    {MP_ROM_QSTR(MP_QSTR_READ), MP_ROM_INT(OB_SCS_INSTR_READ)},
    {MP_ROM_QSTR(MP_QSTR_WRITE), MP_ROM_INT(OB_SCS_INSTR_WRITE)},
    {MP_ROM_QSTR(MP_QSTR_SYNC_WRITE), MP_ROM_INT(OB_SCS_INSTR_SYNC_WRITE)},
    {MP_ROM_QSTR(MP_QSTR_FLAG_VOLTAGE), MP_ROM_INT(OB_SCS_FLAG_VOLTAGE)},
    {MP_ROM_QSTR(MP_QSTR_FLAG_ANGLE), MP_ROM_INT(OB_SCS_FLAG_ANGLE)},
    {MP_ROM_QSTR(MP_QSTR_FLAG_OVERHEAT), MP_ROM_INT(OB_SCS_FLAG_OVERHEAT)},
    {MP_ROM_QSTR(MP_QSTR_FLAG_OVERCURRENT), MP_ROM_INT(OB_SCS_FLAG_OVERCURRENT)},
    {MP_ROM_QSTR(MP_QSTR_FLAG_OVERLOAD), MP_ROM_INT(OB_SCS_FLAG_OVERLOAD)},
    {MP_ROM_QSTR(MP_QSTR_REG_ID), MP_ROM_INT(OB_SCS_REG_ID)},
    {MP_ROM_QSTR(MP_QSTR_REG_RESPONSE_LEVEL), MP_ROM_INT(OB_SCS_REG_RESPONSE_LEVEL)},
    {MP_ROM_QSTR(MP_QSTR_REG_MIN_ANGLE), MP_ROM_INT(OB_SCS_REG_MIN_ANGLE)},
    {MP_ROM_QSTR(MP_QSTR_REG_MAX_ANGLE), MP_ROM_INT(OB_SCS_REG_MAX_ANGLE)},
    {MP_ROM_QSTR(MP_QSTR_REG_MAX_TORQUE), MP_ROM_INT(OB_SCS_REG_MAX_TORQUE)},
    {MP_ROM_QSTR(MP_QSTR_REG_MODE), MP_ROM_INT(OB_SCS_REG_MODE)},
    {MP_ROM_QSTR(MP_QSTR_REG_TORQUE_ENABLE), MP_ROM_INT(OB_SCS_REG_TORQUE_ENABLE)},
    {MP_ROM_QSTR(MP_QSTR_REG_ACCELERATION), MP_ROM_INT(OB_SCS_REG_ACCELERATION)},
    {MP_ROM_QSTR(MP_QSTR_REG_GOAL_POSITION), MP_ROM_INT(OB_SCS_REG_GOAL_POSITION)},
    {MP_ROM_QSTR(MP_QSTR_REG_GOAL_TIME), MP_ROM_INT(OB_SCS_REG_GOAL_TIME)},
    {MP_ROM_QSTR(MP_QSTR_REG_GOAL_SPEED), MP_ROM_INT(OB_SCS_REG_GOAL_SPEED)},
    {MP_ROM_QSTR(MP_QSTR_REG_TORQUE_LIMIT), MP_ROM_INT(OB_SCS_REG_TORQUE_LIMIT)},
    {MP_ROM_QSTR(MP_QSTR_REG_LOCK), MP_ROM_INT(OB_SCS_REG_LOCK)},
    {MP_ROM_QSTR(MP_QSTR_REG_PRESENT_POSITION), MP_ROM_INT(OB_SCS_REG_PRESENT_POSITION)},
    {MP_ROM_QSTR(MP_QSTR_REG_PRESENT_SPEED), MP_ROM_INT(OB_SCS_REG_PRESENT_SPEED)},
    {MP_ROM_QSTR(MP_QSTR_REG_PRESENT_LOAD), MP_ROM_INT(OB_SCS_REG_PRESENT_LOAD)},
    {MP_ROM_QSTR(MP_QSTR_REG_PRESENT_VOLTAGE), MP_ROM_INT(OB_SCS_REG_PRESENT_VOLTAGE)},
    {MP_ROM_QSTR(MP_QSTR_REG_PRESENT_TEMPERATURE), MP_ROM_INT(OB_SCS_REG_PRESENT_TEMPERATURE)},
    {MP_ROM_QSTR(MP_QSTR_REG_MOVING), MP_ROM_INT(OB_SCS_REG_MOVING)},
    {MP_ROM_QSTR(MP_QSTR_REG_PRESENT_CURRENT), MP_ROM_INT(OB_SCS_REG_PRESENT_CURRENT)},
    {MP_ROM_QSTR(MP_QSTR_REG_COUNT), MP_ROM_INT(OB_SCS_REG_COUNT)},
    {MP_ROM_QSTR(MP_QSTR_MODE_POSITION), MP_ROM_INT(OB_SCS_MODE_POSITION)},
    {MP_ROM_QSTR(MP_QSTR_MODE_WHEEL), MP_ROM_INT(OB_SCS_MODE_WHEEL)},
    {MP_ROM_QSTR(MP_QSTR_MODE_DUTY), MP_ROM_INT(OB_SCS_MODE_DUTY)},
    {MP_ROM_QSTR(MP_QSTR_MODE_STEP), MP_ROM_INT(OB_SCS_MODE_STEP)},
    {MP_ROM_QSTR(MP_QSTR_COUNTS_PER_REV), MP_ROM_INT(OB_SCS_COUNTS_PER_REV)},
    {MP_ROM_QSTR(MP_QSTR_MULTI_TURN_SPAN), MP_ROM_INT(OB_SCS_MULTI_TURN_SPAN)},
    {MP_ROM_QSTR(MP_QSTR_POSITION_SIGN_BIT), MP_ROM_INT(OB_SCS_POSITION_SIGN_BIT)},
    {MP_ROM_QSTR(MP_QSTR_SPEED_SIGN_BIT), MP_ROM_INT(OB_SCS_SPEED_SIGN_BIT)},
    {MP_ROM_QSTR(MP_QSTR_LOAD_SIGN_BIT), MP_ROM_INT(OB_SCS_LOAD_SIGN_BIT)},
    {MP_ROM_QSTR(MP_QSTR_DUTY_SIGN_BIT), MP_ROM_INT(OB_SCS_DUTY_SIGN_BIT)},
};
static MP_DEFINE_CONST_DICT(scs_globals, scs_globals_table);

const mp_obj_module_t ob_mp_scs_module = {
    .base = {&mp_type_module},
    .globals = (mp_obj_dict_t *)&scs_globals,
};
