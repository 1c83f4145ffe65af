/*
 * The serial-bus engine: the hub's side of one UART of Feetech SCS servos
 * (ST-3032 wheels, ST-3215 arms) once a DriveBase adopted them.
 *
 * Each adopted servo gets a slot. The servo is switched to its open-loop duty
 * mode and multi-turn position reporting, and from then on the engine, ticked
 * at 1 kHz by motor_process, does its bus work:
 *
 *   1. one SYNC WRITE of every driven slot's duty (goal time register), so
 *      both wheels change at the same packet boundary, and one SYNC WRITE of
 *      torque enable for the slots that started or stopped coasting;
 *   2. position, speed and load reads (one 6-byte READ per slot), round robin
 *      from where the last tick stopped, as many as fit in the tick's bus
 *      budget; a failed read is retried once when the budget allows.
 *
 * A slot's motor IO (ob_motor_io_t, in the adopting motor's user frame, its
 * invert applied) is what a DriveBase or Servo core drives: read_angle gives
 * the latest multi-turn angle and fails while the servo's last read failed,
 * write_duty and write_coast set what the next tick sends. So the control
 * loop runs on the tick with no Python, on the hub and in the simulator.
 *
 * A slot can also run its own position control, the manual's st_move_core:
 * ob_serial_bus_move() and ob_serial_bus_hold() start a trapezoid move or a
 * position lock on the slot (a servo core, servo.h, over the slot's motor
 * IO) that the engine's tick advances before it sends the duties, so a motor
 * a DriveBase adopted keeps its run_angle()/hold() on the tick with no
 * Python. ob_serial_bus_arrived() is the arrival flag, ob_serial_bus_stalled()
 * the stall flag (pushing hard but barely moving, from the servo's feedback).
 * A servo that stops answering shows in its counters: replies, failed reads
 * and failed reads in a row; after OB_SERIAL_BUS_SILENT_READS failures in a
 * row its angle, speed and load read as unavailable, which the runtime turns
 * into the manual's "not responding on the bus" error naming the motor.
 * Garbage, truncated replies and a wrong id answering cost a failed read,
 * never more than the read's deadline.
 */
#ifndef OB_SERIAL_BUS_H
#define OB_SERIAL_BUS_H

#include <stdbool.h>
#include <stdint.h>

#include "ob_types.h"
#include "scs.h"
#include "servo.h"
#include "uart.h"

#define OB_SERIAL_BUS_MAX_SLOTS 8
#define OB_SERIAL_BUS_COUNTS_PER_REV ((int)OB_SCS_COUNTS_PER_REV)
/* Failed reads in a row after which a slot counts as silent. */
#define OB_SERIAL_BUS_SILENT_READS 3u
/* Bus time the tick may spend, out of its 1000 us. */
#define OB_SERIAL_BUS_TICK_BUDGET_US 900u
/* How long a reply may take to complete after its request left the wire (a 12-byte reply is 120 us). */
#define OB_SERIAL_BUS_REPLY_TIMEOUT_US 300u
/* Attempts of the transactions run outside the tick (adopt, release). */
#define OB_SERIAL_BUS_ATTEMPTS 3
#define OB_SERIAL_BUS_DEFAULT_BAUD 1000000u
/* The stall flag's defaults (the ST-3215/ST-3032 drivers' STALL_LOAD_PCT and STALL_SPEED_DPS). */
#define OB_SERIAL_BUS_STALL_LOAD_PCT 80.0f
#define OB_SERIAL_BUS_STALL_SPEED_DPS 20.0f

typedef enum {
    OB_SERIAL_BUS_OK = 0,
    OB_SERIAL_BUS_E_ID = -1,       /* servo id outside 0..253 */
    OB_SERIAL_BUS_E_FULL = -2,     /* every slot is taken */
    OB_SERIAL_BUS_E_ADOPTED = -3,  /* the servo already has a slot */
    OB_SERIAL_BUS_E_SILENT = -4,   /* the servo did not answer */
    OB_SERIAL_BUS_E_SLOT = -5,     /* not an adopted slot */
    OB_SERIAL_BUS_E_COUNTS = -6,   /* counts_per_rev other than the servo's 4096 */
} ob_serial_bus_error_t;

struct ob_serial_bus;

typedef struct {
    struct ob_serial_bus *bus;
    uint8_t servo_id;
    bool adopted;
    float sign; /* -1 when the adopting motor is inverted */
    /* What the next tick sends. */
    bool driven;    /* torque on, at duty_pct; false: coasting */
    float duty_pct; /* user frame, -100..100 */
    /* drive="wheel": the servo's own speed loop (wheel mode) runs duty_pct of wheel_max_dps. */
    bool wheel_mode;
    float wheel_max_dps;
    /* What the servo was told last (torque enable). */
    bool torque_known;
    bool torque_on;
    /* Feedback. */
    bool have_reading;
    int32_t last_raw; /* present position as the servo reported it */
    int32_t counts;   /* multi-turn, servo frame, since adoption */
    float speed_dps;  /* user frame */
    float load_pct;   /* user frame, percent of stall */
    uint8_t status;   /* error flags of the servo's last reply */
    uint32_t replies;
    uint32_t failed_reads;
    uint32_t failed_in_a_row;
    bool move_active; /* st_move_core: the slot's own move or hold (bus->moves[slot]) drives it */
} ob_serial_bus_slot_t;

typedef struct ob_serial_bus {
    ob_uart_t uart;
    uint32_t byte_us;
    uint32_t budget_us;
    uint32_t reply_timeout_us;
    ob_serial_bus_slot_t slots[OB_SERIAL_BUS_MAX_SLOTS];
    int n_slots;   /* slots handed out so far; numbers are never reused */
    int next_read; /* round robin: the slot the next tick reads first */
    /* Counters of the engine as a whole. */
    uint32_t ticks;
    uint32_t last_tick_bus_us; /* wire time the last tick used */
    uint64_t bus_us_total;
    uint32_t garbage_frames; /* frames dropped: bad checksum, wrong id, wrong length */
    /* st_move_core, one per slot, apart from the slots the bus work walks every tick. */
    ob_servo_t moves[OB_SERIAL_BUS_MAX_SLOTS];
} ob_serial_bus_t;

/* An engine over uart at baud, with no slots. */
void ob_serial_bus_init(ob_serial_bus_t *bus, const ob_uart_t *uart, uint32_t baud);

/*
 * Take servo_id onto the engine: ping it, switch it to duty mode with torque
 * off and multi-turn positions, read its position once. On success *slot is
 * its slot number and the servo coasts until its IO is driven.
 */
ob_serial_bus_error_t ob_serial_bus_adopt(ob_serial_bus_t *bus, int servo_id, bool invert, int *slot);

/*
 * How the slot's duty reaches the servo: drive="duty" (wheel_mode false, the
 * default: open-loop duty mode, the engine's controllers close the loop) or
 * drive="wheel" (the servo's internal speed controller in wheel mode, asked
 * for duty_pct of max_dps). Switches the servo's mode at once.
 */
ob_serial_bus_error_t ob_serial_bus_set_drive(ob_serial_bus_t *bus, int slot, bool wheel_mode, float max_dps);

/* Coast the servo, switch it back to wheel mode and free its slot (the number is not reused). */
ob_serial_bus_error_t ob_serial_bus_release(ob_serial_bus_t *bus, int slot);

/* The slot's state, or NULL when slot is not adopted. */
ob_serial_bus_slot_t *ob_serial_bus_slot(ob_serial_bus_t *bus, int slot);

/* The slot's motor IO (user frame); its ctx is the slot. */
ob_motor_io_t ob_serial_bus_motor_io(ob_serial_bus_slot_t *slot);

/* False while the slot is silent (OB_SERIAL_BUS_SILENT_READS failures in a row) or never read. */
bool ob_serial_bus_answering(const ob_serial_bus_slot_t *slot);

/* Multi-turn angle in degrees, user frame. */
float ob_serial_bus_angle_deg(const ob_serial_bus_slot_t *slot);

/* True when some slot is adopted (the engine has bus work to do each tick). */
bool ob_serial_bus_active(const ob_serial_bus_t *bus);

/*
 * st_move_core. A move of angle_deg (relative, run_angle's direction rule) at
 * speed_dps with the given acceleration (magnitude; 0: the core's default),
 * ending in then; or a hold where the shaft is. Either makes the slot's own
 * controller its driver until ob_serial_bus_end_move() (a DriveBase or
 * another controller taking the slot back), which leaves the output as is.
 */
void ob_serial_bus_move(ob_serial_bus_slot_t *slot, float speed_dps, float angle_deg, ob_then_t then,
                        float accel_dps2);
void ob_serial_bus_hold(ob_serial_bus_slot_t *slot);
void ob_serial_bus_end_move(ob_serial_bus_slot_t *slot);

/* The arrival flag: no move is active, or it reached its target (a hold never ends). */
bool ob_serial_bus_arrived(const ob_serial_bus_slot_t *slot);

/* The move lost the servo's feedback and was halted (coasting). */
bool ob_serial_bus_move_lost_feedback(const ob_serial_bus_slot_t *slot);

/*
 * The stall flag: the servo pushes at least load_pct of its stall load while
 * turning at most speed_dps (the drivers' STALL_LOAD_PCT / STALL_SPEED_DPS),
 * or the slot's move stalled. False while the slot is silent.
 */
bool ob_serial_bus_stalled(const ob_serial_bus_slot_t *slot, float load_pct, float speed_dps);

/* One tick's bus work (an ob_tick_fn_t; ctx is the engine). */
void ob_serial_bus_tick(void *ctx, uint32_t now_ms);

/* Text for an ob_serial_bus_error_t, for the bindings' messages. */
const char *ob_serial_bus_strerror(ob_serial_bus_error_t error);

#endif /* OB_SERIAL_BUS_H */
