/*
 * One H-bridge channel (L298N, TB6612) as a motor's actuator: a signed duty
 * in percent becomes direction-pin levels and a PWM duty (hbridge_pins.h).
 *
 *     IN1 IN2  EN      bridge
 *      1   0   duty    forward
 *      0   1   duty    reverse
 *      1   1   full    brake (the winding is shorted)
 *      0   0   0       coast (outputs off)
 *
 * Sign is direction in the user's frame; `invert` flips it for a motor
 * mounted mirror-image. A duty of exactly 0 brakes: a controller that asks
 * for no drive wants the wheel held by its own back-EMF, not let go (coast
 * is its own call). Out-of-range duties are clamped to +-100; a NaN coasts,
 * since nothing sensible can be driven from it and the tick cannot raise.
 *
 * The levels last written are kept, so a binding can report what the pins
 * carry; a write that repeats them is skipped (the controller writes every
 * millisecond, mostly the same duty).
 */
#ifndef OB_HBRIDGE_H
#define OB_HBRIDGE_H

#include <stdbool.h>
#include <stdint.h>

#include "hbridge_pins.h"

/* PWM frequencies a bridge takes: below, a geared motor audibly jerks each period; above, an
 * L298N's bipolar switches spend the period switching and a TB6612 is past its 100 kHz rating. */
#define OB_HBRIDGE_FREQ_MIN_HZ 10
#define OB_HBRIDGE_FREQ_MAX_HZ 100000

/* freq_hz when a binding is given none: the L298N's (its bipolar switches are slow). */
#define OB_HBRIDGE_DEFAULT_FREQ_HZ 1000

/* The widest duty a pin set may offer: a 20-bit LEDC timer's 2^20 (the ESP32's widest). */
#define OB_HBRIDGE_DUTY_BITS_MAX 20
#define OB_HBRIDGE_DUTY_MAX_LIMIT (1u << OB_HBRIDGE_DUTY_BITS_MAX)

/* Duty scale of a bridge with no pins (levels only kept): machine.PWM's duty_u16. */
#define OB_HBRIDGE_UNWIRED_DUTY_MAX 65535u

typedef enum {
    OB_HBRIDGE_COAST = 0,
    OB_HBRIDGE_BRAKE,
    OB_HBRIDGE_FORWARD,
    OB_HBRIDGE_REVERSE,
} ob_hbridge_state_t;

typedef enum {
    OB_HBRIDGE_OK = 0,
    OB_HBRIDGE_BAD_FREQ,     /* freq_hz outside OB_HBRIDGE_FREQ_MIN_HZ..OB_HBRIDGE_FREQ_MAX_HZ */
    OB_HBRIDGE_BAD_DUTY_MAX, /* the pins' duty_max outside 1..OB_HBRIDGE_DUTY_MAX_LIMIT */
} ob_hbridge_error_t;

typedef struct {
    bool invert;      /* forward drives the bridge's reverse: a motor mounted mirror-image */
    uint32_t freq_hz; /* EN's PWM frequency (the pins' owner sets the peripheral up at it) */
} ob_hbridge_config_t;

typedef struct {
    bool in1;
    bool in2;
    uint32_t duty; /* out of the pins' duty_max */
} ob_hbridge_levels_t;

typedef struct {
    ob_hbridge_config_t cfg;
    ob_hbridge_pins_t pins;     /* write NULL: nothing wired, the levels are only kept */
    ob_hbridge_state_t state;   /* what the pins do (invert applied) */
    float duty_pct;             /* the duty driven, user frame, after clamping; 0 braking or coasting */
    ob_hbridge_levels_t levels; /* what the pins were last told */
    bool levels_valid;          /* false until a write succeeded (and after one failed): write again */
    uint32_t writes;            /* writes that reached the pins */
    uint32_t write_errors;      /* writes the pins refused */
} ob_hbridge_t;

/* An L298N channel's defaults: not inverted, freq_hz as given. */
void ob_hbridge_default_config(ob_hbridge_config_t *cfg, uint32_t freq_hz);

/* OB_HBRIDGE_OK when cfg can drive a bridge: what a binding checks before it sets up the PWM. */
ob_hbridge_error_t ob_hbridge_check_config(const ob_hbridge_config_t *cfg);

/*
 * Take the bridge over pins (NULL: none wired) and coast it. Nothing changes
 * unless the config and the pins' duty_max are valid.
 */
ob_hbridge_error_t ob_hbridge_init(ob_hbridge_t *hb, const ob_hbridge_config_t *cfg, const ob_hbridge_pins_t *pins);

/* The levels a state at duty_pct (0..100, the magnitude) puts on the pins, out of duty_max. */
ob_hbridge_levels_t ob_hbridge_levels_for(ob_hbridge_state_t state, float duty_pct, uint32_t duty_max);

/* Drive at duty_pct (-100..100, user frame): 0 brakes, NaN coasts, beyond +-100 is clamped. */
void ob_hbridge_drive(ob_hbridge_t *hb, float duty_pct);

/* Short the winding. */
void ob_hbridge_brake(ob_hbridge_t *hb);

/* Switch the outputs off: the motor spins down freely. */
void ob_hbridge_coast(ob_hbridge_t *hb);

/* Let go of the pins: coast them, then keep only the levels (the owner is about to free the pins). */
void ob_hbridge_unwire(ob_hbridge_t *hb);

/* The pins' duty scale (OB_HBRIDGE_UNWIRED_DUTY_MAX without pins). */
uint32_t ob_hbridge_duty_max(const ob_hbridge_t *hb);

/* A motor IO's write_duty and write_coast (ob_types.h) over a bridge (ctx: ob_hbridge_t *). */
void ob_hbridge_write_duty(void *ctx, float duty_pct);
void ob_hbridge_write_coast(void *ctx);

/* "coast", "brake", "forward", "reverse". */
const char *ob_hbridge_state_name(ob_hbridge_state_t state);

/* Text for an ob_hbridge_error_t, for the bindings' messages. */
const char *ob_hbridge_strerror(ob_hbridge_error_t error);

#endif /* OB_HBRIDGE_H */
