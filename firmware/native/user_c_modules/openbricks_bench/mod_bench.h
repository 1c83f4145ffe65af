/*
 * What the _openbricks_bench module's files share: the Python types, and the
 * emulated bus behind a BenchBus object (a BenchIMU rides on its wheels).
 */
#ifndef OB_MOD_BENCH_H
#define OB_MOD_BENCH_H

#include "bench_servos.h"
#include "py/obj.h"

extern const mp_obj_type_t ob_mp_bench_bus_type;
extern const mp_obj_type_t ob_mp_bench_encoder_type;
extern const mp_obj_type_t ob_mp_bench_imu_type;
extern const mp_obj_type_t ob_mp_bench_dc_motor_type;

/* The emulated bus of a BenchBus object, or NULL for any other object. */
ob_bench_bus_t *ob_bench_bus_get(mp_obj_t obj);

#endif /* OB_MOD_BENCH_H */
