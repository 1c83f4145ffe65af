/*
 * The hard tick: a 1 kHz periodic callback below the interpreter, for what
 * must run every millisecond whatever Python is doing (the serial-bus engine
 * over the hub's UART).
 *
 * The platform delivers the period (hard_timer.h: ESP-IDF's esp_timer on the
 * hub, a POSIX thread on host builds) and calls ob_hard_tick_fire() from its
 * own context; this file keeps the count and the verdict of the self-test
 * the manual names (motor_process.hard_tick_selftest() / hard_tick_count()).
 * With a work function set it is also what runs motor_process on the hub
 * and the unix port: each period it tries the motor lock and, when every
 * subscriber is native, ticks the controllers and the serial-bus engine
 * right there, so a busy interpreter never starves them.
 * Before that work it polls the sensors registered with it (a PCNT
 * encoder's counter, the ICM-45686's SPI burst), so a counter is unwrapped
 * and the gyro heading integrated every millisecond whoever reads them.
 * Nothing here may allocate, block or call the interpreter.
 */
#ifndef OB_HARD_TICK_H
#define OB_HARD_TICK_H

#include <stdbool.h>
#include <stdint.h>

#define OB_HARD_TICK_PERIOD_US 1000u
/* A self-test passes when at least this share of the expected ticks arrived (and no more than 1/share). */
#define OB_HARD_TICK_MIN_SHARE_PCT 90u
/* How long a self-test lets a timer it just started run before counting. */
#define OB_HARD_TICK_SETTLE_MS 5u
/* How long a self-test waits for ticks a busy host's timer thread still owes (0 lost, some late). */
#define OB_HARD_TICK_GRACE_MS 100u

/*
 * What a period runs in the timer's context, under the motor lock
 * (hard_timer.h): the control tick of motor_process when everything
 * subscribed is native (a DriveBase or Servo on native motor IO, a bus engine
 * on a native UART). Returns true when it ran the control tick.
 */
typedef bool (*ob_hard_tick_work_fn_t)(void *ctx);

/* A sensor read each period, under the motor lock, before the work (never allocates or blocks). */
typedef void (*ob_hard_tick_poll_fn_t)(void *ctx);

/* Sensors one hard tick polls at most: the ESP32's 8 PCNT units and a few IMUs. */
#define OB_HARD_TICK_MAX_POLLS 12u

typedef struct {
    volatile uint32_t count;      /* periods delivered since the hard tick started */
    volatile uint32_t dispatched; /* periods that ran the control tick in the timer's context */
    volatile uint32_t contended;  /* periods skipped because the interpreter held the motor lock */
    bool running;
    ob_hard_tick_work_fn_t work; /* NULL: the tick only counts */
    void *work_ctx;
    ob_hard_tick_poll_fn_t poll_fn[OB_HARD_TICK_MAX_POLLS];
    void *poll_ctx[OB_HARD_TICK_MAX_POLLS];
    volatile uint32_t n_polls;
} ob_hard_tick_t;

void ob_hard_tick_init(ob_hard_tick_t *tick);

/* One period elapsed: called by the platform timer, in its context; counts, then runs the work under the lock. */
void ob_hard_tick_fire(ob_hard_tick_t *tick);

/*
 * Poll fn(ctx) every period from now on; false when OB_HARD_TICK_MAX_POLLS
 * sensors are polled already. Called holding the motor lock (or before the
 * timer starts), like every change to what the tick runs.
 */
bool ob_hard_tick_add_poll(ob_hard_tick_t *tick, ob_hard_tick_poll_fn_t fn, void *ctx);

/* Stop polling ctx (nothing when it is not polled); holding the motor lock. */
void ob_hard_tick_remove_poll(ob_hard_tick_t *tick, void *ctx);

/* Ticks a 1 kHz tick should deliver in elapsed_us. */
uint32_t ob_hard_tick_expected(uint32_t elapsed_us);

/* True when `ticks` counted over elapsed_us is a working 1 kHz tick (within OB_HARD_TICK_MIN_SHARE_PCT). */
bool ob_hard_tick_rate_ok(uint32_t ticks, uint32_t elapsed_us);

#endif /* OB_HARD_TICK_H */
