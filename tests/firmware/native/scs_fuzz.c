/*
 * Bounds and invariant checker for the SCS codec, built by test_scs.py with
 * AddressSanitizer and UBSan. Every input is copied into a heap block of
 * exactly its length, so a single byte read past the end aborts the process.
 *
 *   scs_fuzz stdin               records "<u16 little-endian length><bytes>" on stdin,
 *                                one "ok" line per record (for hypothesis)
 *   scs_fuzz random N SEED       N generated cases: random, mutated and truncated
 *                                packets, and encoder calls with random capacities
 *
 * A broken invariant prints what broke and aborts.
 */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "scs.h"

#define CHECK(cond, ...)                                                                                  \
    do {                                                                                                  \
        if (!(cond)) {                                                                                    \
            fprintf(stderr, "scs_fuzz: %s:%d: %s: ", __FILE__, __LINE__, #cond);                        \
            fprintf(stderr, __VA_ARGS__);                                                                 \
            fputc('\n', stderr);                                                                          \
            abort();                                                                                      \
        }                                                                                                 \
    } while (0)

static void check_frame(const uint8_t *buf, size_t len, ob_scs_parse_t r, const ob_scs_frame_t *f,
                        int status) {
    CHECK(r <= OB_SCS_PARSE_BAD_LENGTH, "result %d", (int)r);
    CHECK(f->consumed <= len, "consumed %zu of %zu", f->consumed, len);
    if (r == OB_SCS_PARSE_OK) {
        size_t frame_len = OB_SCS_FRAME_OVERHEAD + f->param_len;
        CHECK(f->consumed >= frame_len, "consumed %zu < frame %zu", f->consumed, frame_len);
        CHECK((f->params == NULL) == (f->param_len == 0), "params %p with %zu bytes", (const void *)f->params,
              f->param_len);
        if (f->param_len > 0) {
            CHECK(f->params >= buf && f->params + f->param_len <= buf + len, "params outside the input");
        }
        CHECK(!status || f->id <= OB_SCS_MAX_SERVO_ID, "status from id %u", f->id);
        /* What was accepted is exactly what the encoder makes of the decoded fields. */
        uint8_t again[OB_SCS_MAX_FRAME];
        int n = ob_scs_encode_frame(f->id, f->code, f->params, f->param_len, again, sizeof again);
        CHECK(n == (int)frame_len, "re-encode gave %d", n);
        CHECK(memcmp(again, buf + f->consumed - frame_len, frame_len) == 0, "re-encoded frame differs");
    } else if (r == OB_SCS_PARSE_NEED_MORE) {
        CHECK(f->needed >= 1, "need_more with needed 0");
    } else {
        CHECK(f->consumed >= 1, "rejected frame consumed nothing: no progress");
    }
}

/* Parse the whole input the way a receive loop would: drop `consumed`, parse again. */
static void drain(const uint8_t *data, size_t len, int status) {
    uint8_t *buf = malloc(len > 0 ? len : 1);
    CHECK(buf != NULL, "out of memory");
    memcpy(buf, data, len);
    size_t at = 0;
    for (;;) {
        ob_scs_frame_t f;
        /* A zero-length input gets a NULL pointer, which is valid with len 0. */
        const uint8_t *p = len - at > 0 ? buf + at : NULL;
        ob_scs_parse_t r = status ? ob_scs_parse_status(p, len - at, &f) : ob_scs_parse_frame(p, len - at, &f);
        check_frame(p, len - at, r, &f, status);
        at += f.consumed;
        if (r == OB_SCS_PARSE_NEED_MORE) {
            break;
        }
    }
    free(buf);
}

static void run_input(const uint8_t *data, size_t len) {
    drain(data, len, 0);
    drain(data, len, 1);
}

/* xorshift64*: reproducible from the seed, no libc rand() state. */
static uint64_t rng_state;

static uint32_t rnd(void) {
    rng_state ^= rng_state >> 12;
    rng_state ^= rng_state << 25;
    rng_state ^= rng_state >> 27;
    return (uint32_t)((rng_state * 2685821657736338717ull) >> 32);
}

static uint8_t rnd_byte(void) {
    return (uint8_t)rnd();
}

/* A valid packet of a random kind, written to out; returns its length. */
static size_t random_packet(uint8_t *out) {
    uint8_t data[OB_SCS_MAX_PARAMS];
    uint8_t ids[OB_SCS_MAX_PARAMS];
    for (size_t i = 0; i < sizeof data; i++) {
        data[i] = rnd_byte();
        ids[i] = (uint8_t)(rnd() % (OB_SCS_MAX_SERVO_ID + 1u));
    }
    int n;
    switch (rnd() % 5) {
    case 0:
        n = ob_scs_encode_ping(rnd_byte(), out, OB_SCS_MAX_FRAME);
        break;
    case 1:
        n = ob_scs_encode_read(rnd_byte(), rnd_byte(), rnd_byte(), out, OB_SCS_MAX_FRAME);
        break;
    case 2:
        n = ob_scs_encode_write(rnd_byte(), rnd_byte() & 0x7Fu, data, 1u + rnd() % 8u, out, OB_SCS_MAX_FRAME);
        break;
    case 3:
        n = ob_scs_encode_sync_write(rnd_byte() & 0x7Fu, (uint8_t)(1u + rnd() % 4u), ids, data, 1u + rnd() % 6u,
                                     out, OB_SCS_MAX_FRAME);
        break;
    default:
        n = ob_scs_encode_status(rnd_byte(), rnd_byte(), data, rnd() % 12u, out, OB_SCS_MAX_FRAME);
        break;
    }
    /* Random ids and registers are sometimes refused; fall back to a ping that always encodes. */
    if (n < 0) {
        n = ob_scs_encode_ping(1, out, OB_SCS_MAX_FRAME);
    }
    return (size_t)n;
}

static void random_parse_case(void) {
    uint8_t buf[4 * OB_SCS_MAX_FRAME];
    size_t len = 0;
    unsigned pieces = 1u + rnd() % 4u;
    for (unsigned i = 0; i < pieces; i++) {
        if (rnd() % 3 == 0) {
            /* Garbage, sometimes rich in header bytes. */
            size_t g = rnd() % 16u;
            for (size_t j = 0; j < g && len < sizeof buf; j++) {
                buf[len++] = rnd() % 2 ? 0xFFu : rnd_byte();
            }
        } else if (len + OB_SCS_MAX_FRAME <= sizeof buf) {
            len += random_packet(buf + len);
        }
    }
    /* Mutate: flip bytes, then maybe cut the tail off. */
    unsigned flips = rnd() % 3u;
    for (unsigned i = 0; i < flips && len > 0; i++) {
        buf[rnd() % len] ^= (uint8_t)(1u + rnd() % 255u);
    }
    if (len > 0 && rnd() % 2) {
        len = rnd() % len;
    }
    run_input(buf, len);
}

/* Encoders with random arguments and an output block of exactly cap bytes. */
static void random_encode_case(void) {
    uint8_t data[OB_SCS_MAX_FRAME];
    uint8_t ids[OB_SCS_MAX_FRAME];
    for (size_t i = 0; i < sizeof data; i++) {
        data[i] = rnd_byte();
        ids[i] = rnd_byte();
    }
    size_t cap = rnd() % (OB_SCS_MAX_FRAME + 8u);
    uint8_t *out = malloc(cap > 0 ? cap : 1);
    CHECK(out != NULL, "out of memory");
    size_t n_data = rnd() % 260u;
    int n;
    switch (rnd() % 6) {
    case 0:
        n = ob_scs_encode_ping(rnd_byte(), out, cap);
        break;
    case 1:
        n = ob_scs_encode_read(rnd_byte(), rnd_byte(), rnd_byte(), out, cap);
        break;
    case 2:
        n = ob_scs_encode_write(rnd_byte(), rnd_byte(), data, n_data, out, cap);
        break;
    case 3:
        n = ob_scs_encode_sync_write(rnd_byte(), rnd_byte(), ids, data, rnd() % 130u, out, cap);
        break;
    case 4:
        n = ob_scs_encode_status(rnd_byte(), rnd_byte(), data, n_data, out, cap);
        break;
    default:
        n = ob_scs_encode_frame(rnd_byte(), rnd_byte(), data, n_data, out, cap);
        break;
    }
    CHECK(n <= (int)cap, "encoder wrote %d bytes into %zu", n, cap);
    if (n >= 0) {
        ob_scs_frame_t f;
        CHECK(ob_scs_parse_frame(out, (size_t)n, &f) == OB_SCS_PARSE_OK, "encoded packet does not parse");
        CHECK(f.consumed == (size_t)n, "parse consumed %zu of %d", f.consumed, n);
    } else {
        CHECK(n >= OB_SCS_E_REGISTER, "unknown error code %d", n);
    }
    free(out);
}

static int run_stdin(void) {
    static uint8_t record[0x10000];
    for (;;) {
        uint8_t head[2];
        if (fread(head, 1, 2, stdin) != 2) {
            return 0;
        }
        size_t len = (size_t)head[0] | ((size_t)head[1] << 8);
        CHECK(fread(record, 1, len, stdin) == len, "short record");
        run_input(record, len);
        puts("ok");
        fflush(stdout);
    }
}

int main(int argc, char **argv) {
    if (argc == 2 && strcmp(argv[1], "stdin") == 0) {
        return run_stdin();
    }
    if (argc == 4 && strcmp(argv[1], "random") == 0) {
        long cases = strtol(argv[2], NULL, 10);
        rng_state = strtoull(argv[3], NULL, 10) * 0x9E3779B97F4A7C15ull + 1u;
        for (long i = 0; i < cases; i++) {
            if (i % 2) {
                random_encode_case();
            } else {
                random_parse_case();
            }
        }
        printf("ok %ld\n", cases);
        return 0;
    }
    fprintf(stderr, "usage: %s stdin | random N SEED\n", argv[0]);
    return 2;
}
