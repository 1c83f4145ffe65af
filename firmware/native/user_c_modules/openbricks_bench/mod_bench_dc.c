/*
 * _openbricks_bench.BenchDCMotor: an emulated DC gear motor with its encoder
 * (bench_dc_motor.c), wired the way the hub wires one, for the unix port's
 * hard-tick tests of the DC drive path.
 *
 *     motor = BenchDCMotor(no_load_dps=1230, counts_per_rev=1320)   # a JGB37-520 1:30
 *     bridge = HBridge(outputs=motor.pins())       # the H-bridge core drives its terminals
 *     enc = PCNTEncoder(1320, counter=motor.counter())   # a PCNT unit counts its encoder
 *
 * pins() is a native H-bridge pin set and counter() a native counter
 * (mp_bindings.h), so a controller over bridge.motor_io(enc, ...) reads and
 * drives this motor with no Python call, in the hard tick, as on the hub.
 * angle_deg() is the true shaft angle; levels() what the bridge last wrote.
 * Methods run under the motor lock.
 */
#include "bench_dc_motor.h"
#include "hard_timer.h"
#include "mod_bench.h"
#include "mp_bindings.h"

/* EN's scale on the emulated pins: an LEDC timer's at 1 kHz (16 bits). */
#define DUTY_MAX 65536u

typedef struct {
    mp_obj_base_t base;
    ob_bench_dc_motor_t motor;
    mp_obj_t pins;    /* the pin set and the counter, made once: each keeps this object alive */
    mp_obj_t counter;
} bench_dc_obj_t;

typedef struct {
    ob_mp_native_hbridge_pins_t base;
    bench_dc_obj_t *owner;
} bench_dc_pins_obj_t;

typedef struct {
    ob_mp_native_counter_t base;
    bench_dc_obj_t *owner;
} bench_dc_counter_obj_t;

static MP_DEFINE_CONST_OBJ_TYPE(
    bench_dc_pins_type,
    MP_QSTR_BenchDCMotorPins,
    MP_TYPE_FLAG_NONE,
    parent, &ob_mp_native_hbridge_pins_type
    );

static MP_DEFINE_CONST_OBJ_TYPE(
    bench_dc_counter_type,
    MP_QSTR_BenchDCMotorCounter,
    MP_TYPE_FLAG_NONE,
    parent, &ob_mp_native_counter_type
    );

/* ---- The links as the cores see them: no Python. ---- */

static bool pins_write(void *ctx, bool in1, bool in2, uint32_t duty) {
    ob_bench_dc_motor_write(&((bench_dc_obj_t *)ctx)->motor, in1, in2, duty, ob_hard_timer_now_us());
    return true;
}

static bool counter_read(void *ctx, int32_t *raw) {
    *raw = ob_bench_dc_motor_read(&((bench_dc_obj_t *)ctx)->motor, ob_hard_timer_now_us());
    return true;
}

/* ---- Python. ---- */

static mp_obj_t bench_dc_make_new(const mp_obj_type_t *type, size_t n_args, size_t n_kw, const mp_obj_t *all_args) {
    enum { ARG_no_load_dps, ARG_counts_per_rev };
    static const mp_arg_t allowed[] = {
        {MP_QSTR_no_load_dps, MP_ARG_OBJ, {.u_obj = MP_OBJ_NULL}},
        {MP_QSTR_counts_per_rev, MP_ARG_OBJ, {.u_obj = MP_OBJ_NULL}},
    };
    mp_arg_val_t args[MP_ARRAY_SIZE(allowed)];
    mp_arg_parse_all_kw_array(n_args, n_kw, all_args, MP_ARRAY_SIZE(allowed), allowed, args);
    float no_load_dps = args[ARG_no_load_dps].u_obj == MP_OBJ_NULL
                            ? 1230.0f
                            : ob_mp_positive_float(args[ARG_no_load_dps].u_obj, "BenchDCMotor()", "no_load_dps");
    float cpr = args[ARG_counts_per_rev].u_obj == MP_OBJ_NULL
                    ? 1320.0f
                    : ob_mp_positive_float(args[ARG_counts_per_rev].u_obj, "BenchDCMotor()", "counts_per_rev");
    bench_dc_obj_t *self = mp_obj_malloc(bench_dc_obj_t, type);
    ob_bench_dc_motor_init(&self->motor, no_load_dps, cpr, DUTY_MAX, ob_hard_timer_now_us());
    bench_dc_pins_obj_t *pins = mp_obj_malloc(bench_dc_pins_obj_t, &bench_dc_pins_type);
    pins->base.pins = (ob_hbridge_pins_t){pins_write, DUTY_MAX, self};
    pins->owner = self;
    bench_dc_counter_obj_t *counter = mp_obj_malloc(bench_dc_counter_obj_t, &bench_dc_counter_type);
    counter->base.pcnt = (ob_pcnt_t){counter_read, self};
    counter->owner = self;
    self->pins = MP_OBJ_FROM_PTR(pins);
    self->counter = MP_OBJ_FROM_PTR(counter);
    return MP_OBJ_FROM_PTR(self);
}

static mp_obj_t bench_dc_pins(mp_obj_t self_in) {
    return ((bench_dc_obj_t *)MP_OBJ_TO_PTR(self_in))->pins;
}
static MP_DEFINE_CONST_FUN_OBJ_1(bench_dc_pins_obj, bench_dc_pins);

static mp_obj_t bench_dc_counter(mp_obj_t self_in) {
    return ((bench_dc_obj_t *)MP_OBJ_TO_PTR(self_in))->counter;
}
static MP_DEFINE_CONST_FUN_OBJ_1(bench_dc_counter_obj, bench_dc_counter);

static mp_obj_t bench_dc_angle_deg(mp_obj_t self_in) {
    bench_dc_obj_t *self = MP_OBJ_TO_PTR(self_in);
    return mp_obj_new_float(ob_bench_dc_motor_angle_deg(&self->motor, ob_hard_timer_now_us()));
}
static MP_DEFINE_CONST_FUN_OBJ_1(bench_dc_angle_deg_obj, bench_dc_angle_deg);

static mp_obj_t bench_dc_speed_dps(mp_obj_t self_in) {
    bench_dc_obj_t *self = MP_OBJ_TO_PTR(self_in);
    ob_bench_dc_motor_angle_deg(&self->motor, ob_hard_timer_now_us()); /* brings the speed up to now */
    return mp_obj_new_float(self->motor.speed_cps * 360.0 / self->motor.counts_per_rev);
}
static MP_DEFINE_CONST_FUN_OBJ_1(bench_dc_speed_dps_obj, bench_dc_speed_dps);

static mp_obj_t bench_dc_levels(mp_obj_t self_in) {
    bench_dc_obj_t *self = MP_OBJ_TO_PTR(self_in);
    mp_obj_t items[3] = {mp_obj_new_bool(self->motor.in1), mp_obj_new_bool(self->motor.in2),
                         mp_obj_new_int_from_uint(self->motor.duty)};
    return mp_obj_new_tuple(3, items);
}
static MP_DEFINE_CONST_FUN_OBJ_1(bench_dc_levels_obj, bench_dc_levels);

static mp_obj_t bench_dc_writes(mp_obj_t self_in) {
    return mp_obj_new_int_from_uint(((bench_dc_obj_t *)MP_OBJ_TO_PTR(self_in))->motor.writes);
}
static MP_DEFINE_CONST_FUN_OBJ_1(bench_dc_writes_obj, bench_dc_writes);

static mp_obj_t bench_dc_reads(mp_obj_t self_in) {
    return mp_obj_new_int_from_uint(((bench_dc_obj_t *)MP_OBJ_TO_PTR(self_in))->motor.encoder.reads);
}
static MP_DEFINE_CONST_FUN_OBJ_1(bench_dc_reads_obj, bench_dc_reads);

static const mp_rom_map_elem_t bench_dc_locals_table[] = {
    {MP_ROM_QSTR(MP_QSTR_pins), MP_ROM_PTR(&bench_dc_pins_obj)},
    {MP_ROM_QSTR(MP_QSTR_counter), MP_ROM_PTR(&bench_dc_counter_obj)},
    {MP_ROM_QSTR(MP_QSTR_angle_deg), MP_ROM_PTR(&bench_dc_angle_deg_obj)},
    {MP_ROM_QSTR(MP_QSTR_speed_dps), MP_ROM_PTR(&bench_dc_speed_dps_obj)},
    {MP_ROM_QSTR(MP_QSTR_levels), MP_ROM_PTR(&bench_dc_levels_obj)},
    {MP_ROM_QSTR(MP_QSTR_writes), MP_ROM_PTR(&bench_dc_writes_obj)},
    {MP_ROM_QSTR(MP_QSTR_reads), MP_ROM_PTR(&bench_dc_reads_obj)},
};
static MP_DEFINE_CONST_DICT(bench_dc_locals, bench_dc_locals_table);

static void bench_dc_attr(mp_obj_t self_in, qstr attr, mp_obj_t *dest) {
    ob_mp_locked_attr(self_in, attr, dest, &bench_dc_locals); /* the hard tick may be driving it */
}

MP_DEFINE_CONST_OBJ_TYPE(
    ob_mp_bench_dc_motor_type,
    MP_QSTR_BenchDCMotor,
    MP_TYPE_FLAG_NONE,
    make_new, bench_dc_make_new,
    attr, bench_dc_attr,
    locals_dict, &bench_dc_locals
    );
