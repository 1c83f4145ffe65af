/*
 * _openbricks_native for MicroPython: the control cores of firmware/native/
 * bound one file per core (mp_<core>.c), mirroring the host binding
 * (firmware/native/bindings/cpython/py_<core>.c): the same names, arguments,
 * defaults, results and error messages, so runtime code and tests read the
 * same on the hub and in the simulator.
 *
 * What only the hub has: motor_process ticks itself from a 1 ms timer on
 * ESP-IDF builds (mp_scheduler.c), and interrupt_main() raises
 * KeyboardInterrupt in the main thread for the launcher's stop button.
 * What only the host has: MotorIO and the C-API capsule, which let the
 * simulator's wheels plug into the cores in C.
 */
#ifndef OB_MP_BINDINGS_H
#define OB_MP_BINDINGS_H

#include <stdbool.h>
#include <stdint.h>

#include "py/obj.h"
#include "py/runtime.h"

/* MicroPython 1.25 renamed NORETURN to MP_NORETURN; accept either. */
#ifndef MP_NORETURN
#define MP_NORETURN NORETURN
#endif

#include "ob_types.h"
#include "scheduler.h"

/* ---- Argument checks (mp_args.c): every binding rejects bad input the same way, with a
 * TypeError or ValueError naming the callable and the argument. ---- */

/* A real, finite number that fits a float (int or float; bool and str are refused). */
float ob_mp_float(mp_obj_t obj, const char *where, const char *name);

/* As ob_mp_float, and > 0. */
float ob_mp_positive_float(mp_obj_t obj, const char *where, const char *name);

/* An int (bool refused) that fits 32 bits. */
int32_t ob_mp_int32(mp_obj_t obj, const char *where, const char *name);

/* A scheduler time: a non-negative int, taken modulo 2^32 like the hub's tick clock. */
uint32_t ob_mp_time_ms(mp_obj_t obj, const char *where);

/* The manual's then= strings: "coast", "stop", "brake", "hold", "continue". */
ob_then_t ob_mp_then(mp_obj_t obj, const char *where);

/* Canonical name of a then value, for reporting state. */
const char *ob_mp_then_name(ob_then_t then);

/* None when absent: MP_OBJ_NULL (an omitted optional argument) and None read the same. */
static inline bool ob_mp_given(mp_obj_t obj) {
    return obj != MP_OBJ_NULL && obj != mp_const_none;
}

/* ---- Native subscribers (mp_scheduler.c). ----
 *
 * motor_process ticks Servo and DriveBase through a C function pointer, with
 * no Python call. Their object structs start with this header; their types
 * name ob_mp_subscriber_type as parent. A tick_fn never raises: an exception
 * from an IO callable is left in `error`, and motor_process raises the first
 * one after every subscriber of the tick ran (one failing motor must not stop
 * the others being controlled). */
typedef struct {
    mp_obj_base_t base;
    ob_tick_fn_t tick_fn; /* NULL: built without IO, drive it with update() */
    void *tick_ctx;
    mp_obj_t error;       /* first exception of the current call, or MP_OBJ_NULL */
    bool hard_safe;       /* tick_fn calls no Python and allocates nothing: the hard tick may run it */
} ob_mp_subscriber_t;

extern const mp_obj_type_t ob_mp_subscriber_type;

/* Keep the first exception of a call; print (not lose) any later one. */
void ob_mp_subscriber_stash(ob_mp_subscriber_t *sub, mp_obj_t exc);

/* Raise the stashed exception, if any, clearing it. */
void ob_mp_subscriber_raise(ob_mp_subscriber_t *sub);

/* ---- Native motor IO and wires (mp_motor_io.c). ----
 *
 * A MotorIO object carries an ob_motor_io_t whose functions never call
 * Python (a serial-bus engine's slot): a Servo(io=) or DriveBase(left_io=,
 * right_io=) over it ticks with no Python call, so the hard tick may run it.
 * A native UART (a type deriving from ob_mp_native_uart_type: a host test's
 * in-memory bus) hands the serial-bus engine an ob_uart_t the same way. */
typedef struct {
    mp_obj_base_t base;
    ob_motor_io_t io;
} ob_mp_motor_io_t;

extern const mp_obj_type_t ob_mp_motor_io_type;

/* True and *io filled when obj is a MotorIO whose provider set its functions. */
bool ob_mp_motor_io_get(mp_obj_t obj, ob_motor_io_t *io);

#include "uart.h"
typedef struct {
    mp_obj_base_t base;
    ob_uart_t uart;
} ob_mp_native_uart_t;

extern const mp_obj_type_t ob_mp_native_uart_type;

/* The ob_uart_t of a native UART object, or NULL for any other object. */
const ob_uart_t *ob_mp_native_uart_get(mp_obj_t obj);

/* Native sensor links, the same way: a counter a PCNTEncoder reads (pcnt.h) and an SPI link an
 * ICM45686 reads (spi.h). On the hub they are the peripherals; in the unix port's tests, emulated
 * hardware in C (_openbricks_bench). A sensor on a native link is polled by the hard tick. */
#include "pcnt.h"
#include "spi.h"
typedef struct {
    mp_obj_base_t base;
    ob_pcnt_t pcnt;
} ob_mp_native_counter_t;

typedef struct {
    mp_obj_base_t base;
    ob_spi_t spi;
} ob_mp_native_spi_t;

extern const mp_obj_type_t ob_mp_native_counter_type;
extern const mp_obj_type_t ob_mp_native_spi_type;

/* The ob_pcnt_t / ob_spi_t of a native counter / SPI link, or NULL for any other object. */
const ob_pcnt_t *ob_mp_native_counter_get(mp_obj_t obj);
const ob_spi_t *ob_mp_native_spi_get(mp_obj_t obj);

/* An H-bridge's pins the same way (hbridge_pins.h): on the hub GPIO and LEDC, in the unix port's
 * tests an emulated DC motor in C (_openbricks_bench) that turns as the levels say. */
#include "hbridge_pins.h"
typedef struct {
    mp_obj_base_t base;
    ob_hbridge_pins_t pins;
} ob_mp_native_hbridge_pins_t;

extern const mp_obj_type_t ob_mp_native_hbridge_pins_type;

/* The ob_hbridge_pins_t of a native H-bridge pin set, or NULL for any other object. */
const ob_hbridge_pins_t *ob_mp_native_hbridge_pins_get(mp_obj_t obj);

/* ---- The hard tick and the motor lock (mp_hard_tick.c, mp_hard_lock.c). ---- */

/* Start the 1 kHz hard tick (idempotent); raises OSError when the platform timer cannot start. */
void ob_mp_hard_tick_start(void);

/*
 * Have the hard tick call fn(ctx) every period, before motor_process (hard_tick.h), and keep
 * `owner` (the object ctx lives in) alive meanwhile; starts the hard tick. Raises OSError when it
 * polls as many sensors as it can already.
 */
#include "hard_tick.h"
void ob_mp_hard_tick_poll(mp_obj_t owner, ob_hard_tick_poll_fn_t fn, void *ctx);

/* Stop polling ctx and let go of its owner (nothing when it is not polled). */
void ob_mp_hard_tick_unpoll(void *ctx);

/* Run by the hard tick each period under the motor lock (mp_scheduler.c): ticks motor_process when
 * every subscriber is hard-safe; true when it did. */
bool ob_mp_motor_process_hard_work(void *unused);

/* True while the hard tick runs motor_process by itself (everything subscribed is hard-safe). */
bool ob_mp_motor_process_hard_ticked(void);

/* For a type's attr slot: a method of locals_dict, loaded, comes back bound to self and called under
 * the motor lock, so the interpreter never changes a controller in the middle of a hard tick.
 * Anything else continues the normal lookup. Stores are refused (read-only). */
void ob_mp_locked_attr(mp_obj_t self_in, qstr attr, mp_obj_t *dest, const mp_obj_dict_t *locals_dict);

/* ---- Types and objects of the module. ---- */

extern const mp_obj_type_t ob_mp_profile_type;
extern const mp_obj_type_t ob_mp_observer_type;
extern const mp_obj_type_t ob_mp_motor_process_type;
extern const mp_obj_type_t ob_mp_servo_type;
extern const mp_obj_type_t ob_mp_drivebase_type;
extern const mp_obj_type_t ob_mp_imu_yaw_type;
extern const mp_obj_type_t ob_mp_pcnt_encoder_type;
extern const mp_obj_type_t ob_mp_icm45686_type;
extern const mp_obj_type_t ob_mp_hbridge_type;

#include "encoder.h"
/* The encoder core of an open PCNTEncoder (mp_encoder.c), or NULL for anything else: an H-bridge's
 * motor_io() reads it in C. */
ob_encoder_t *ob_mp_pcnt_encoder_get(mp_obj_t obj);

#include "drivebase.h"
/* True and *source filled when obj is an ICM45686 (mp_icm45686.c): a DriveBase reads its heading in C. */
bool ob_mp_icm45686_heading_source(mp_obj_t obj, ob_heading_source_t *source);
extern const mp_obj_module_t ob_mp_scs_module;
extern const mp_obj_type_t ob_mp_serial_bus_type;
/* serial_bus(uart_id, tx=None, rx=None, baud=1000000, dir_pin=None) -> SerialBus (mp_serial_bus.c). */
extern const mp_obj_fun_builtin_var_t ob_mp_serial_bus_obj;
/* motor_process.hard_tick_count() / hard_tick_selftest(duration_ms=100) (mp_hard_tick.c). */
extern const mp_obj_fun_builtin_fixed_t ob_mp_hard_tick_count_obj;
extern const mp_obj_fun_builtin_var_t ob_mp_hard_tick_selftest_obj;

#if defined(ESP_PLATFORM)
#include "uart.h"
/* The hub's UART uart_id on the ESP-IDF driver, as the engine's wire (mp_uart_esp32.c); raises on failure. */
const ob_uart_t *ob_mp_uart_esp32_open(int uart_id, mp_obj_t tx, mp_obj_t rx, uint32_t baud, mp_obj_t dir_pin);
#endif

#if defined(ESP_PLATFORM)
#include "pcnt.h"
/*
 * A PCNT unit counting both edges of pin_a and pin_b (x4 quadrature) between -OB_PCNT_LIMIT and
 * +OB_PCNT_LIMIT behind a glitch filter of filter_cycles APB cycles (mp_pcnt_esp32.c); fills *pcnt.
 * Raises OSError when the unit cannot be set up.
 */
void ob_mp_pcnt_esp32_open(int pin_a, int pin_b, int filter_cycles, ob_pcnt_t *pcnt);

/* Stop the unit *pcnt counts on and give it back to the driver. */
void ob_mp_pcnt_esp32_close(const ob_pcnt_t *pcnt);

#include "spi.h"
/*
 * The SPI bus spi_id on sck/mosi/miso with one device on cs at hz and SPI mode `mode`, for a sensor
 * core read in the hard tick (mp_spi_esp32.c); fills *spi. Raises OSError when it cannot be set up.
 */
void ob_mp_spi_esp32_open(int spi_id, int sck, int mosi, int miso, int cs, uint32_t hz, int mode, ob_spi_t *spi);

/* Remove the device and free the bus opened for *spi. */
void ob_mp_spi_esp32_close(const ob_spi_t *spi);

/*
 * IN1/IN2 on in1/in2 as GPIO outputs and EN's PWM on an LEDC channel at freq_hz (mp_hbridge_esp32.c),
 * all low; fills *pins. Raises ValueError for a pin that cannot drive an output, OSError when no LEDC
 * channel or timer is free or the peripheral refuses.
 */
void ob_mp_hbridge_esp32_open(int in1, int in2, int pwm, uint32_t freq_hz, ob_hbridge_pins_t *pins);

/* Stop the PWM (EN low), give the channel and its timer back, and leave IN1/IN2 low. */
void ob_mp_hbridge_esp32_close(const ob_hbridge_pins_t *pins);
#endif

/* The module's motor_process (created on first use; see mp_scheduler.c). */
mp_obj_t ob_mp_motor_process_get(void);

#endif /* OB_MP_BINDINGS_H */
