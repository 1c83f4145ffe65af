/*
 * _openbricks_bench.BenchBus: emulated ST-3032s on an in-memory wire
 * (bench_servos.c, on the shared servo emulation of emulated_servo.c) for
 * the unix port's tests.
 *
 *     bus = BenchBus((1, 2))        # servo ids; no_load_dps=888 (the ST-3032's)
 *     uart = bus                    # what machine.UART(1, ...) hands the drivers
 *
 * It is a UART to Python (write, read, any, deinit: the servo drivers talk
 * to it before a DriveBase adopts them) and a native UART to the serial-bus
 * engine (ob_mp_native_uart_t), so the engine over it calls no Python and
 * the hard tick runs it from its own thread while the interpreter is busy.
 * Its methods run under the motor lock, as the engine's do. angle_deg(id)
 * is the true shaft angle; set_silent(id, True) unplugs a servo.
 * BenchEncoder and BenchIMU (mod_bench_sensors.c) are emulated sensors on
 * native links, for the hard tick to poll; BenchDCMotor (mod_bench_dc.c) a DC
 * gear motor an H-bridge drives and a PCNT unit counts.
 */
#include <string.h>

#include "bench_servos.h"
#include "hard_timer.h"
#include "mod_bench.h"
#include "mp_bindings.h"

typedef struct {
    ob_mp_native_uart_t base;
    ob_bench_bus_t bus;
} bench_bus_obj_t;

/* ---- The wire as the engine sees it (ob_uart_t): no Python. ---- */

static bool wire_write(void *ctx, const uint8_t *data, size_t n) {
    bench_bus_obj_t *self = ctx;
    ob_emu_bus_write(&self->bus.wire, data, n, ob_hard_timer_now_us());
    return true;
}

static size_t wire_read(void *ctx, uint8_t *buf, size_t cap, uint32_t timeout_us) {
    (void)timeout_us; /* replies are in at once; nothing more will come */
    return ob_emu_bus_read(&((bench_bus_obj_t *)ctx)->bus.wire, buf, cap);
}

static void wire_flush_input(void *ctx) {
    ((bench_bus_obj_t *)ctx)->bus.wire.reply_len = 0;
}

static uint32_t wire_now_us(void *ctx) {
    (void)ctx;
    return ob_hard_timer_now_us();
}

/* ---- Python. ---- */

static ob_bench_servo_t *servo_arg(bench_bus_obj_t *self, mp_obj_t id_in) {
    mp_int_t id = mp_obj_get_int(id_in);
    ob_bench_servo_t *servo = id >= 0 && id <= OB_SCS_MAX_SERVO_ID ? ob_bench_bus_find(&self->bus, (uint8_t)id) : NULL;
    if (servo == NULL) {
        mp_raise_msg_varg(&mp_type_ValueError, MP_ERROR_TEXT("BenchBus: no servo with id %d on this bus"), (int)id);
    }
    return servo;
}

static mp_obj_t bench_bus_make_new(const mp_obj_type_t *type, size_t n_args, size_t n_kw, const mp_obj_t *args) {
    enum { ARG_ids, ARG_no_load_dps };
    static const mp_arg_t allowed[] = {
        {MP_QSTR_ids, MP_ARG_REQUIRED | MP_ARG_OBJ, {.u_obj = MP_OBJ_NULL}},
        {MP_QSTR_no_load_dps, MP_ARG_OBJ, {.u_obj = MP_OBJ_NULL}},
    };
    mp_arg_val_t vals[MP_ARRAY_SIZE(allowed)];
    mp_arg_parse_all_kw_array(n_args, n_kw, args, MP_ARRAY_SIZE(allowed), allowed, vals);
    float no_load_dps = vals[ARG_no_load_dps].u_obj == MP_OBJ_NULL
                            ? 888.0f
                            : ob_mp_positive_float(vals[ARG_no_load_dps].u_obj, "BenchBus()", "no_load_dps");
    bench_bus_obj_t *self = mp_obj_malloc(bench_bus_obj_t, type);
    ob_bench_bus_init(&self->bus, no_load_dps);
    self->base.uart = (ob_uart_t){wire_write, wire_read, wire_flush_input, wire_now_us, self};
    size_t n;
    mp_obj_t *ids;
    mp_obj_get_array(vals[ARG_ids].u_obj, &n, &ids);
    for (size_t i = 0; i < n; i++) {
        mp_int_t id = mp_obj_get_int(ids[i]);
        if (id < 0 || id > OB_SCS_MAX_SERVO_ID || ob_bench_bus_add(&self->bus, (uint8_t)id, ob_hard_timer_now_us()) == NULL) {
            mp_raise_msg_varg(&mp_type_ValueError,
                              MP_ERROR_TEXT("BenchBus(): servo id %d is outside 0..253, repeated, or one too many "
                                            "(at most %d servos)"),
                              (int)id, OB_BENCH_MAX_SERVOS);
        }
    }
    return MP_OBJ_FROM_PTR(self);
}

static mp_obj_t bench_bus_write(mp_obj_t self_in, mp_obj_t data_in) {
    bench_bus_obj_t *self = MP_OBJ_TO_PTR(self_in);
    mp_buffer_info_t info;
    mp_get_buffer_raise(data_in, &info, MP_BUFFER_READ);
    wire_write(self, info.buf, info.len);
    return MP_OBJ_NEW_SMALL_INT((mp_int_t)info.len);
}
static MP_DEFINE_CONST_FUN_OBJ_2(bench_bus_write_obj, bench_bus_write);

static mp_obj_t bench_bus_read(size_t n_args, const mp_obj_t *args) {
    bench_bus_obj_t *self = MP_OBJ_TO_PTR(args[0]);
    size_t cap = self->bus.wire.reply_len;
    if (n_args > 1 && args[1] != mp_const_none) {
        mp_int_t want = mp_obj_get_int(args[1]);
        cap = want < 0 ? cap : ((size_t)want < cap ? (size_t)want : cap);
    }
    if (cap == 0) {
        return mp_const_none; /* as machine.UART with timeout=0: nothing waiting */
    }
    uint8_t buf[sizeof(self->bus.wire.reply)];
    size_t n = ob_emu_bus_read(&self->bus.wire, buf, cap);
    return mp_obj_new_bytes(buf, n);
}
static MP_DEFINE_CONST_FUN_OBJ_VAR_BETWEEN(bench_bus_read_obj, 1, 2, bench_bus_read);

static mp_obj_t bench_bus_any(mp_obj_t self_in) {
    bench_bus_obj_t *self = MP_OBJ_TO_PTR(self_in);
    return MP_OBJ_NEW_SMALL_INT((mp_int_t)self->bus.wire.reply_len);
}
static MP_DEFINE_CONST_FUN_OBJ_1(bench_bus_any_obj, bench_bus_any);

static mp_obj_t bench_bus_deinit(mp_obj_t self_in) {
    (void)self_in; /* an in-memory wire has nothing to close; the engine keeps using it */
    return mp_const_none;
}
static MP_DEFINE_CONST_FUN_OBJ_1(bench_bus_deinit_obj, bench_bus_deinit);

static mp_obj_t bench_bus_angle_deg(mp_obj_t self_in, mp_obj_t id_in) {
    bench_bus_obj_t *self = MP_OBJ_TO_PTR(self_in);
    ob_bench_servo_t *servo = servo_arg(self, id_in);
    return mp_obj_new_float(ob_bench_servo_angle_deg(servo, self->bus.no_load_cps, ob_hard_timer_now_us()));
}
static MP_DEFINE_CONST_FUN_OBJ_2(bench_bus_angle_deg_obj, bench_bus_angle_deg);

static mp_obj_t bench_bus_set_silent(mp_obj_t self_in, mp_obj_t id_in, mp_obj_t silent_in) {
    servo_arg(MP_OBJ_TO_PTR(self_in), id_in)->firmware->silent = mp_obj_is_true(silent_in);
    return mp_const_none;
}
static MP_DEFINE_CONST_FUN_OBJ_3(bench_bus_set_silent_obj, bench_bus_set_silent);

static mp_obj_t bench_bus_packets(mp_obj_t self_in) {
    return mp_obj_new_int_from_uint(((bench_bus_obj_t *)MP_OBJ_TO_PTR(self_in))->bus.wire.packets);
}
static MP_DEFINE_CONST_FUN_OBJ_1(bench_bus_packets_obj, bench_bus_packets);

static const mp_rom_map_elem_t bench_bus_locals_table[] = {
    {MP_ROM_QSTR(MP_QSTR_write), MP_ROM_PTR(&bench_bus_write_obj)},
    {MP_ROM_QSTR(MP_QSTR_read), MP_ROM_PTR(&bench_bus_read_obj)},
    {MP_ROM_QSTR(MP_QSTR_any), MP_ROM_PTR(&bench_bus_any_obj)},
    {MP_ROM_QSTR(MP_QSTR_deinit), MP_ROM_PTR(&bench_bus_deinit_obj)},
    {MP_ROM_QSTR(MP_QSTR_angle_deg), MP_ROM_PTR(&bench_bus_angle_deg_obj)},
    {MP_ROM_QSTR(MP_QSTR_set_silent), MP_ROM_PTR(&bench_bus_set_silent_obj)},
    {MP_ROM_QSTR(MP_QSTR_packets), MP_ROM_PTR(&bench_bus_packets_obj)},
};
static MP_DEFINE_CONST_DICT(bench_bus_locals, bench_bus_locals_table);

static void bench_bus_attr(mp_obj_t self_in, qstr attr, mp_obj_t *dest) {
    ob_mp_locked_attr(self_in, attr, dest, &bench_bus_locals); /* the hard tick may be using the wire */
}

MP_DEFINE_CONST_OBJ_TYPE(
    ob_mp_bench_bus_type,
    MP_QSTR_BenchBus,
    MP_TYPE_FLAG_NONE,
    make_new, bench_bus_make_new,
    attr, bench_bus_attr,
    locals_dict, &bench_bus_locals,
    parent, &ob_mp_native_uart_type
    );

static const mp_rom_map_elem_t bench_globals_table[] = {
    {MP_ROM_QSTR(MP_QSTR___name__), MP_ROM_QSTR(MP_QSTR__openbricks_bench)},
    {MP_ROM_QSTR(MP_QSTR_BenchBus), MP_ROM_PTR(&ob_mp_bench_bus_type)},
    {MP_ROM_QSTR(MP_QSTR_BenchEncoder), MP_ROM_PTR(&ob_mp_bench_encoder_type)},
    {MP_ROM_QSTR(MP_QSTR_BenchIMU), MP_ROM_PTR(&ob_mp_bench_imu_type)},
    {MP_ROM_QSTR(MP_QSTR_BenchDCMotor), MP_ROM_PTR(&ob_mp_bench_dc_motor_type)},
};
static MP_DEFINE_CONST_DICT(bench_globals, bench_globals_table);

ob_bench_bus_t *ob_bench_bus_get(mp_obj_t obj) {
    return mp_obj_is_type(obj, &ob_mp_bench_bus_type) ? &((bench_bus_obj_t *)MP_OBJ_TO_PTR(obj))->bus : NULL;
}

const mp_obj_module_t ob_mp_bench_module = {
    .base = {&mp_type_module},
    .globals = (mp_obj_dict_t *)&bench_globals,
};

MP_REGISTER_MODULE(MP_QSTR__openbricks_bench, ob_mp_bench_module);
