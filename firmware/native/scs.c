/*
 * Feetech SCS/STS packet codec: see scs.h for the frame and the contracts.
 */
#include "scs.h"

#define SCS_HEADER_BYTE 0xFFu
/* Offsets inside a frame that starts at its first header byte. */
#define SCS_AT_ID 2u
#define SCS_AT_LEN 3u
#define SCS_AT_CODE 4u
#define SCS_AT_PARAMS 5u
/* LEN counts CODE and CHECKSUM besides the parameters. */
#define SCS_LEN_EXTRA 2u

const char *ob_scs_strerror(int code) {
    switch (code) {
    case OB_SCS_E_NULL:
        return "a required buffer pointer is NULL";
    case OB_SCS_E_BUFFER:
        return "output buffer too small for the packet";
    case OB_SCS_E_ID:
        return "servo ID not addressable by this instruction (servo IDs are 0..253, broadcast is 254)";
    case OB_SCS_E_LENGTH:
        return "data length is zero or the packet would exceed 253 parameter bytes";
    case OB_SCS_E_REGISTER:
        return "register address plus length runs past register 0xFF";
    default:
        return "unknown SCS codec error";
    }
}

uint8_t ob_scs_checksum(const uint8_t *bytes, size_t n) {
    unsigned sum = 0;
    for (size_t i = 0; i < n; i++) {
        sum += bytes[i];
    }
    return (uint8_t)(~sum & 0xFFu);
}

/*
 * Write the frame head and return where the parameters go; the checksum is
 * computed over the finished frame by scs_seal, so the encoders that lay out
 * their parameters in place (sync write) need no staging copy.
 */
static uint8_t *scs_open(uint8_t *out, uint8_t id, uint8_t code, size_t n) {
    out[0] = SCS_HEADER_BYTE;
    out[1] = SCS_HEADER_BYTE;
    out[SCS_AT_ID] = id;
    out[SCS_AT_LEN] = (uint8_t)(n + SCS_LEN_EXTRA);
    out[SCS_AT_CODE] = code;
    return out + SCS_AT_PARAMS;
}

static int scs_seal(uint8_t *out, size_t n) {
    size_t body = SCS_AT_PARAMS - SCS_AT_ID + n;
    out[SCS_AT_PARAMS + n] = ob_scs_checksum(out + SCS_AT_ID, body);
    return (int)(OB_SCS_FRAME_OVERHEAD + n);
}

/* Checks shared by every encoder, in the order a caller would want them reported. */
static int scs_check_frame(uint8_t id, const uint8_t *params, size_t n, const uint8_t *out, size_t cap) {
    if (out == NULL || (params == NULL && n > 0)) {
        return OB_SCS_E_NULL;
    }
    if (id > OB_SCS_BROADCAST_ID) {
        return OB_SCS_E_ID;
    }
    if (n > OB_SCS_MAX_PARAMS) {
        return OB_SCS_E_LENGTH;
    }
    if (cap < OB_SCS_FRAME_OVERHEAD + n) {
        return OB_SCS_E_BUFFER;
    }
    return 0;
}

int ob_scs_encode_frame(uint8_t id, uint8_t code, const uint8_t *params, size_t n, uint8_t *out,
                        size_t cap) {
    int err = scs_check_frame(id, params, n, out, cap);
    if (err < 0) {
        return err;
    }
    uint8_t *p = scs_open(out, id, code, n);
    for (size_t i = 0; i < n; i++) {
        p[i] = params[i];
    }
    return scs_seal(out, n);
}

int ob_scs_encode_ping(uint8_t id, uint8_t *out, size_t cap) {
    return ob_scs_encode_frame(id, OB_SCS_INSTR_PING, NULL, 0, out, cap);
}

/* A register span that wraps past 0xFF would address registers the caller never meant. */
static int scs_check_span(uint8_t reg, size_t n) {
    if (n == 0) {
        return OB_SCS_E_LENGTH;
    }
    if ((size_t)reg + n > 0x100u) {
        return OB_SCS_E_REGISTER;
    }
    return 0;
}

int ob_scs_encode_read(uint8_t id, uint8_t reg, uint8_t n, uint8_t *out, size_t cap) {
    if (out == NULL) {
        return OB_SCS_E_NULL;
    }
    if (id > OB_SCS_MAX_SERVO_ID) {
        return OB_SCS_E_ID;
    }
    /* The reply carries n parameters, so n is bounded like any frame's. */
    if (n > OB_SCS_MAX_PARAMS) {
        return OB_SCS_E_LENGTH;
    }
    int err = scs_check_span(reg, n);
    if (err < 0) {
        return err;
    }
    const uint8_t params[2] = {reg, n};
    return ob_scs_encode_frame(id, OB_SCS_INSTR_READ, params, sizeof params, out, cap);
}

int ob_scs_encode_write(uint8_t id, uint8_t reg, const uint8_t *data, size_t n, uint8_t *out, size_t cap) {
    if (out == NULL || data == NULL) {
        return OB_SCS_E_NULL;
    }
    if (id > OB_SCS_BROADCAST_ID) {
        return OB_SCS_E_ID;
    }
    if (n > OB_SCS_MAX_PARAMS - 1u) {
        return OB_SCS_E_LENGTH;
    }
    int err = scs_check_span(reg, n);
    if (err < 0) {
        return err;
    }
    err = scs_check_frame(id, data, n + 1u, out, cap);
    if (err < 0) {
        return err;
    }
    uint8_t *p = scs_open(out, id, OB_SCS_INSTR_WRITE, n + 1u);
    p[0] = reg;
    for (size_t i = 0; i < n; i++) {
        p[1 + i] = data[i];
    }
    return scs_seal(out, n + 1u);
}

int ob_scs_encode_sync_write(uint8_t reg, uint8_t data_len, const uint8_t *ids, const uint8_t *data,
                             size_t count, uint8_t *out, size_t cap) {
    if (out == NULL || ids == NULL || data == NULL) {
        return OB_SCS_E_NULL;
    }
    if (count == 0) {
        return OB_SCS_E_LENGTH;
    }
    int err = scs_check_span(reg, data_len);
    if (err < 0) {
        return err;
    }
    /* Parameters: reg, data_len, then one (id, data...) row per servo. Bound count before multiplying. */
    size_t row = 1u + data_len;
    if (count > (OB_SCS_MAX_PARAMS - 2u) / row) {
        return OB_SCS_E_LENGTH;
    }
    for (size_t i = 0; i < count; i++) {
        if (ids[i] > OB_SCS_MAX_SERVO_ID) {
            return OB_SCS_E_ID;
        }
    }
    size_t n = 2u + count * row;
    if (cap < OB_SCS_FRAME_OVERHEAD + n) {
        return OB_SCS_E_BUFFER;
    }
    uint8_t *p = scs_open(out, OB_SCS_BROADCAST_ID, OB_SCS_INSTR_SYNC_WRITE, n);
    *p++ = reg;
    *p++ = data_len;
    for (size_t i = 0; i < count; i++) {
        *p++ = ids[i];
        for (size_t j = 0; j < data_len; j++) {
            *p++ = data[i * data_len + j];
        }
    }
    return scs_seal(out, n);
}

int ob_scs_encode_status(uint8_t id, uint8_t error_flags, const uint8_t *params, size_t n, uint8_t *out,
                         size_t cap) {
    if (out == NULL) {
        return OB_SCS_E_NULL;
    }
    /* A reply names the servo that sent it; the broadcast address cannot answer. */
    if (id > OB_SCS_MAX_SERVO_ID) {
        return OB_SCS_E_ID;
    }
    return ob_scs_encode_frame(id, error_flags, params, n, out, cap);
}

ob_scs_parse_t ob_scs_parse_frame(const uint8_t *buf, size_t len, ob_scs_frame_t *frame) {
    if (frame == NULL || (buf == NULL && len > 0)) {
        return OB_SCS_PARSE_BAD_ARGUMENT;
    }
    frame->consumed = 0;
    frame->needed = 0;
    frame->id = 0;
    frame->code = 0;
    frame->params = NULL;
    frame->param_len = 0;

    /*
     * Find the last 0xFF of the first run of two or more: the frame starts
     * one byte before it. Extra 0xFF bytes are preamble, since no ID is 0xFF.
     */
    size_t start = 0;
    for (;;) {
        while (start < len && buf[start] != SCS_HEADER_BYTE) {
            start++;
        }
        if (start + 1 >= len) {
            /* Garbage only, or a lone trailing 0xFF that may begin the next header. */
            frame->consumed = start;
            frame->needed = OB_SCS_FRAME_OVERHEAD - (len - start);
            return OB_SCS_PARSE_NEED_MORE;
        }
        if (buf[start + 1] == SCS_HEADER_BYTE) {
            break;
        }
        start += 2;
    }
    while (start + SCS_AT_ID < len && buf[start + SCS_AT_ID] == SCS_HEADER_BYTE) {
        start++;
    }
    frame->consumed = start;

    size_t have = len - start;
    if (have <= SCS_AT_LEN) {
        frame->needed = OB_SCS_FRAME_OVERHEAD - have;
        return OB_SCS_PARSE_NEED_MORE;
    }
    uint8_t len_byte = buf[start + SCS_AT_LEN];
    if (len_byte < SCS_LEN_EXTRA) {
        frame->consumed = start + 1u;
        return OB_SCS_PARSE_BAD_LENGTH;
    }
    size_t total = SCS_AT_LEN + 1u + len_byte;
    if (have < total) {
        frame->needed = total - have;
        return OB_SCS_PARSE_NEED_MORE;
    }

    const uint8_t *f = buf + start;
    size_t n = (size_t)len_byte - SCS_LEN_EXTRA;
    if (ob_scs_checksum(f + SCS_AT_ID, total - SCS_AT_ID - 1u) != f[total - 1u]) {
        frame->consumed = start + 1u;
        return OB_SCS_PARSE_BAD_CHECKSUM;
    }
    frame->consumed = start + total;
    frame->id = f[SCS_AT_ID];
    frame->code = f[SCS_AT_CODE];
    frame->param_len = n;
    frame->params = n > 0 ? f + SCS_AT_PARAMS : NULL;
    return OB_SCS_PARSE_OK;
}

ob_scs_parse_t ob_scs_parse_status(const uint8_t *buf, size_t len, ob_scs_frame_t *status) {
    ob_scs_parse_t result = ob_scs_parse_frame(buf, len, status);
    if (result == OB_SCS_PARSE_OK && status->id > OB_SCS_MAX_SERVO_ID) {
        /* Rescan from the byte after the header start, as for any rejected frame. */
        size_t frame_len = OB_SCS_FRAME_OVERHEAD + status->param_len;
        status->consumed = status->consumed - frame_len + 1u;
        status->id = 0;
        status->code = 0;
        status->params = NULL;
        status->param_len = 0;
        return OB_SCS_PARSE_BAD_HEADER;
    }
    return result;
}

const char *ob_scs_flag_name(unsigned bit) {
    switch (bit) {
    case 0:
        return "voltage";
    case 1:
        return "angle";
    case 2:
        return "overheat";
    case 3:
        return "overcurrent";
    case 5:
        return "overload";
    default:
        return NULL;
    }
}

uint16_t ob_scs_sm_encode(int32_t value, unsigned sign_bit) {
    if (sign_bit < 1u || sign_bit > 15u) {
        return 0;
    }
    uint32_t max_magnitude = (1u << sign_bit) - 1u;
    /* Negate in unsigned arithmetic: -INT32_MIN does not exist as an int32_t. */
    uint32_t magnitude = value < 0 ? 0u - (uint32_t)value : (uint32_t)value;
    if (magnitude > max_magnitude) {
        magnitude = max_magnitude;
    }
    uint32_t sign = (value < 0 && magnitude != 0) ? (1u << sign_bit) : 0u;
    return (uint16_t)(sign | magnitude);
}

int32_t ob_scs_sm_decode(uint16_t raw, unsigned sign_bit) {
    if (sign_bit < 1u || sign_bit > 15u) {
        return 0;
    }
    int32_t magnitude = (int32_t)(raw & ((1u << sign_bit) - 1u));
    return (raw & (1u << sign_bit)) ? -magnitude : magnitude;
}
