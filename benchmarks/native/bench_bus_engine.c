/*
 * The serial-bus engine's tick with two adopted wheels, over an in-memory 1 Mbaud wire.
 *
 * The wire answers like two ST-3032s in duty mode (position, speed and load
 * reads; sync-written duties) and keeps the line's clock: every byte costs
 * 10 us and a reply starts 20 us after its request, as the simulator's wire
 * does. Prints, one per line: the engine's CPU time per tick (best and median
 * of 7 runs, ns) and the wire time one tick used (us).
 */
#define _POSIX_C_SOURCE 199309L /* clock_gettime */

#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "scs.h"
#include "serial_bus.h"

#define TICKS 200000
#define RUNS 7
#define RETURN_DELAY_US 20u

typedef struct {
    uint32_t clock_us;
    uint32_t byte_us;
    uint8_t reply[32];
    size_t reply_len;
    int32_t position[2];
} wire_t;

static bool wire_write(void *ctx, const uint8_t *data, size_t n) {
    wire_t *w = ctx;
    w->clock_us += (uint32_t)n * w->byte_us;
    w->reply_len = 0;
    ob_scs_frame_t frame;
    if (ob_scs_parse_frame(data, n, &frame) != OB_SCS_PARSE_OK || frame.id == OB_SCS_BROADCAST_ID) {
        return true;
    }
    uint8_t params[6] = {0};
    size_t count = 0;
    if (frame.code == OB_SCS_INSTR_READ && frame.id >= 1 && frame.id <= 2) {
        int32_t *position = &w->position[frame.id - 1];
        *position += 3;
        ob_scs_put_u16(params, ob_scs_sm_encode(*position, 15));
        ob_scs_put_u16(params + 2, ob_scs_sm_encode(3000, 15));
        ob_scs_put_u16(params + 4, ob_scs_sm_encode(250, 10));
        count = 6;
    }
    int len = ob_scs_encode_status(frame.id, 0, params, count, w->reply, sizeof(w->reply));
    w->reply_len = len > 0 ? (size_t)len : 0;
    return true;
}

static size_t wire_read(void *ctx, uint8_t *buf, size_t cap, uint32_t timeout_us) {
    wire_t *w = ctx;
    if (w->reply_len == 0) {
        w->clock_us += timeout_us;
        return 0;
    }
    size_t n = w->reply_len < cap ? w->reply_len : cap;
    memcpy(buf, w->reply, n);
    w->clock_us += RETURN_DELAY_US + (uint32_t)n * w->byte_us;
    w->reply_len = 0;
    return n;
}

static void wire_flush(void *ctx) {
    ((wire_t *)ctx)->reply_len = 0;
}

static uint32_t wire_now(void *ctx) {
    return ((wire_t *)ctx)->clock_us;
}

static double now_ns(void) {
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec * 1e9 + (double)ts.tv_nsec;
}

static int compare(const void *a, const void *b) {
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

int main(void) {
    static wire_t wire;
    static ob_serial_bus_t bus;
    wire.byte_us = ob_uart_byte_us(1000000u);
    ob_uart_t uart = {wire_write, wire_read, wire_flush, wire_now, &wire};
    ob_serial_bus_init(&bus, &uart, 1000000u);
    int slots[2];
    if (ob_serial_bus_adopt(&bus, 1, false, &slots[0]) != OB_SERIAL_BUS_OK ||
        ob_serial_bus_adopt(&bus, 2, true, &slots[1]) != OB_SERIAL_BUS_OK) {
        fprintf(stderr, "adoption failed\n");
        return 1;
    }
    ob_motor_io_t io[2] = {ob_serial_bus_motor_io(ob_serial_bus_slot(&bus, slots[0])),
                           ob_serial_bus_motor_io(ob_serial_bus_slot(&bus, slots[1]))};
    double per_tick[RUNS];
    float angle;
    for (int run = 0; run < RUNS; run++) {
        double start = now_ns();
        for (uint32_t t = 0; t < TICKS; t++) {
            ob_serial_bus_tick(&bus, t);
            for (int i = 0; i < 2; i++) {
                (void)io[i].read_angle(io[i].ctx, &angle);
                io[i].write_duty(io[i].ctx, (float)(t % 200u) * 0.25f);
            }
        }
        per_tick[run] = (now_ns() - start) / TICKS;
    }
    qsort(per_tick, RUNS, sizeof(per_tick[0]), compare);
    printf("engine_tick %.1f %.1f\n", per_tick[0], per_tick[RUNS / 2]);
    printf("bus_us %u %u\n", (unsigned)bus.last_tick_bus_us, (unsigned)(bus.bus_us_total / bus.ticks));
    return 0;
}
