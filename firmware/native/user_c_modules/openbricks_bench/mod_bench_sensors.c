/*
 * _openbricks_bench.BenchEncoder and BenchIMU: emulated sensors (bench_sensors.c)
 * on native links, for the unix port's hard-tick tests.
 *
 *     shaft = BenchEncoder(rate_cps=340000)      # an MG370 flat out, seen through a PCNT unit
 *     enc = PCNTEncoder(68028, counter=shaft)    # the hard tick reads it every millisecond
 *
 *     imu_link = BenchIMU(bus, 1, 2, wheel_mm=56, track_mm=120, true_scale=0.9)
 *     imu = ICM45686(imu_link)                   # the hard tick takes a burst every millisecond
 *
 * A BenchEncoder is a native counter and a BenchIMU a native SPI link
 * (mp_bindings.h), so the sensors on them are polled by the hard tick
 * with no Python call, as on the hub. Methods run under the motor lock.
 */
#include "bench_sensors.h"
#include "hard_timer.h"
#include "mod_bench.h"
#include "mp_bindings.h"

/* ---- BenchEncoder. ---- */

typedef struct {
    ob_mp_native_counter_t base;
    ob_bench_shaft_t shaft;
} bench_encoder_obj_t;

static bool shaft_read(void *ctx, int32_t *raw) {
    *raw = ob_bench_shaft_read(&((bench_encoder_obj_t *)ctx)->shaft, ob_hard_timer_now_us());
    return true;
}

static mp_obj_t bench_encoder_make_new(const mp_obj_type_t *type, size_t n_args, size_t n_kw, const mp_obj_t *args) {
    mp_arg_check_num(n_args, n_kw, 0, 1, false);
    bench_encoder_obj_t *self = mp_obj_malloc(bench_encoder_obj_t, type);
    ob_bench_shaft_init(&self->shaft, ob_hard_timer_now_us());
    if (n_args > 0) {
        self->shaft.rate_cps = ob_mp_float(args[0], "BenchEncoder()", "rate_cps");
    }
    self->base.pcnt = (ob_pcnt_t){shaft_read, self};
    return MP_OBJ_FROM_PTR(self);
}

static mp_obj_t bench_encoder_set_rate(mp_obj_t self_in, mp_obj_t rate_in) {
    bench_encoder_obj_t *self = MP_OBJ_TO_PTR(self_in);
    ob_bench_shaft_set_rate(&self->shaft, ob_mp_float(rate_in, "BenchEncoder.set_rate()", "rate_cps"),
                            ob_hard_timer_now_us());
    return mp_const_none;
}
static MP_DEFINE_CONST_FUN_OBJ_2(bench_encoder_set_rate_obj, bench_encoder_set_rate);

static mp_obj_t bench_encoder_true_count(mp_obj_t self_in) {
    bench_encoder_obj_t *self = MP_OBJ_TO_PTR(self_in);
    return mp_obj_new_int_from_ll((long long)ob_bench_shaft_count(&self->shaft, ob_hard_timer_now_us()));
}
static MP_DEFINE_CONST_FUN_OBJ_1(bench_encoder_true_count_obj, bench_encoder_true_count);

static mp_obj_t bench_encoder_reads(mp_obj_t self_in) {
    return mp_obj_new_int_from_uint(((bench_encoder_obj_t *)MP_OBJ_TO_PTR(self_in))->shaft.reads);
}
static MP_DEFINE_CONST_FUN_OBJ_1(bench_encoder_reads_obj, bench_encoder_reads);

static const mp_rom_map_elem_t bench_encoder_locals_table[] = {
    {MP_ROM_QSTR(MP_QSTR_set_rate), MP_ROM_PTR(&bench_encoder_set_rate_obj)},
    {MP_ROM_QSTR(MP_QSTR_true_count), MP_ROM_PTR(&bench_encoder_true_count_obj)},
    {MP_ROM_QSTR(MP_QSTR_reads), MP_ROM_PTR(&bench_encoder_reads_obj)},
};
static MP_DEFINE_CONST_DICT(bench_encoder_locals, bench_encoder_locals_table);

static void bench_encoder_attr(mp_obj_t self_in, qstr attr, mp_obj_t *dest) {
    ob_mp_locked_attr(self_in, attr, dest, &bench_encoder_locals); /* the hard tick may be reading it */
}

MP_DEFINE_CONST_OBJ_TYPE(
    ob_mp_bench_encoder_type,
    MP_QSTR_BenchEncoder,
    MP_TYPE_FLAG_NONE,
    make_new, bench_encoder_make_new,
    attr, bench_encoder_attr,
    locals_dict, &bench_encoder_locals,
    parent, &ob_mp_native_counter_type
    );

/* ---- BenchIMU. ---- */

typedef struct {
    ob_mp_native_spi_t base;
    ob_bench_imu_t imu;
    mp_obj_t bus; /* the BenchBus whose wheels it rides on (kept alive) */
} bench_imu_obj_t;

static bool imu_transfer(void *ctx, const uint8_t *tx, uint8_t *rx, size_t n) {
    return ob_bench_imu_transfer(&((bench_imu_obj_t *)ctx)->imu, tx, rx, n, ob_hard_timer_now_us());
}

static void imu_delay_ms(void *ctx, uint32_t ms) {
    (void)ctx;
    (void)ms; /* the model's registers are usable at once */
}

static mp_obj_t bench_imu_make_new(const mp_obj_type_t *type, size_t n_args, size_t n_kw, const mp_obj_t *all_args) {
    enum { ARG_bus, ARG_left_id, ARG_right_id, ARG_wheel_mm, ARG_track_mm, ARG_right_inverted, ARG_true_scale,
           ARG_bias_dps };
    static const mp_arg_t allowed[] = {
        {MP_QSTR_bus, MP_ARG_REQUIRED | MP_ARG_OBJ, {.u_obj = MP_OBJ_NULL}},
        {MP_QSTR_left_id, MP_ARG_REQUIRED | MP_ARG_INT, {.u_int = 0}},
        {MP_QSTR_right_id, MP_ARG_REQUIRED | MP_ARG_INT, {.u_int = 0}},
        {MP_QSTR_wheel_mm, MP_ARG_KW_ONLY | MP_ARG_REQUIRED | MP_ARG_OBJ, {.u_obj = MP_OBJ_NULL}},
        {MP_QSTR_track_mm, MP_ARG_KW_ONLY | MP_ARG_REQUIRED | MP_ARG_OBJ, {.u_obj = MP_OBJ_NULL}},
        {MP_QSTR_right_inverted, MP_ARG_KW_ONLY | MP_ARG_BOOL, {.u_bool = true}},
        {MP_QSTR_true_scale, MP_ARG_KW_ONLY | MP_ARG_OBJ, {.u_obj = MP_OBJ_NULL}},
        {MP_QSTR_bias_dps, MP_ARG_KW_ONLY | MP_ARG_OBJ, {.u_obj = MP_OBJ_NULL}},
    };
    mp_arg_val_t args[MP_ARRAY_SIZE(allowed)];
    mp_arg_parse_all_kw_array(n_args, n_kw, all_args, MP_ARRAY_SIZE(allowed), allowed, args);
    ob_bench_bus_t *bus = ob_bench_bus_get(args[ARG_bus].u_obj);
    if (bus == NULL) {
        mp_raise_TypeError(MP_ERROR_TEXT("BenchIMU(): bus must be a BenchBus"));
    }
    bench_imu_obj_t *self = mp_obj_malloc(bench_imu_obj_t, type);
    self->bus = args[ARG_bus].u_obj;
    ob_bench_imu_init(&self->imu, bus, (uint8_t)args[ARG_left_id].u_int, (uint8_t)args[ARG_right_id].u_int,
                      args[ARG_right_inverted].u_bool,
                      ob_mp_positive_float(args[ARG_wheel_mm].u_obj, "BenchIMU()", "wheel_mm"),
                      ob_mp_positive_float(args[ARG_track_mm].u_obj, "BenchIMU()", "track_mm"),
                      args[ARG_true_scale].u_obj == MP_OBJ_NULL
                          ? 1.0
                          : (double)ob_mp_positive_float(args[ARG_true_scale].u_obj, "BenchIMU()", "true_scale"),
                      args[ARG_bias_dps].u_obj == MP_OBJ_NULL
                          ? 0.5
                          : (double)ob_mp_float(args[ARG_bias_dps].u_obj, "BenchIMU()", "bias_dps"));
    self->base.spi = (ob_spi_t){imu_transfer, imu_delay_ms, self};
    return MP_OBJ_FROM_PTR(self);
}

static mp_obj_t bench_imu_true_heading(mp_obj_t self_in) {
    bench_imu_obj_t *self = MP_OBJ_TO_PTR(self_in);
    return mp_obj_new_float(ob_bench_imu_true_heading_deg(&self->imu, ob_hard_timer_now_us()));
}
static MP_DEFINE_CONST_FUN_OBJ_1(bench_imu_true_heading_obj, bench_imu_true_heading);

static mp_obj_t bench_imu_bursts(mp_obj_t self_in) {
    return mp_obj_new_int_from_uint(((bench_imu_obj_t *)MP_OBJ_TO_PTR(self_in))->imu.bursts);
}
static MP_DEFINE_CONST_FUN_OBJ_1(bench_imu_bursts_obj, bench_imu_bursts);

static mp_obj_t bench_imu_max_gap_us(mp_obj_t self_in) {
    return mp_obj_new_int_from_uint(((bench_imu_obj_t *)MP_OBJ_TO_PTR(self_in))->imu.max_gap_us);
}
static MP_DEFINE_CONST_FUN_OBJ_1(bench_imu_max_gap_us_obj, bench_imu_max_gap_us);

static mp_obj_t bench_imu_unseen_deg(mp_obj_t self_in) {
    return mp_obj_new_float(((bench_imu_obj_t *)MP_OBJ_TO_PTR(self_in))->imu.unseen_deg);
}
static MP_DEFINE_CONST_FUN_OBJ_1(bench_imu_unseen_deg_obj, bench_imu_unseen_deg);

static const mp_rom_map_elem_t bench_imu_locals_table[] = {
    {MP_ROM_QSTR(MP_QSTR_true_heading), MP_ROM_PTR(&bench_imu_true_heading_obj)},
    {MP_ROM_QSTR(MP_QSTR_bursts), MP_ROM_PTR(&bench_imu_bursts_obj)},
    {MP_ROM_QSTR(MP_QSTR_max_gap_us), MP_ROM_PTR(&bench_imu_max_gap_us_obj)},
    {MP_ROM_QSTR(MP_QSTR_unseen_deg), MP_ROM_PTR(&bench_imu_unseen_deg_obj)},
};
static MP_DEFINE_CONST_DICT(bench_imu_locals, bench_imu_locals_table);

static void bench_imu_attr(mp_obj_t self_in, qstr attr, mp_obj_t *dest) {
    ob_mp_locked_attr(self_in, attr, dest, &bench_imu_locals);
}

MP_DEFINE_CONST_OBJ_TYPE(
    ob_mp_bench_imu_type,
    MP_QSTR_BenchIMU,
    MP_TYPE_FLAG_NONE,
    make_new, bench_imu_make_new,
    attr, bench_imu_attr,
    locals_dict, &bench_imu_locals,
    parent, &ob_mp_native_spi_type
    );
