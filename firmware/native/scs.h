/*
 * Feetech SCS/STS serial-bus packet codec (ST-3215, ST-3032).
 *
 * Every packet on the bus has one frame:
 *
 *     0xFF 0xFF ID LEN CODE PARAM... CHECKSUM
 *
 * where LEN = number of params + 2 and CHECKSUM = ~(ID + LEN + CODE + sum(PARAM)).
 * CODE is the instruction in a host request and the error flags in a servo's
 * status reply; the framing is otherwise identical, so one parser serves the
 * hub (decoding replies) and a simulated servo (decoding requests).
 *
 * The codec never allocates and never touches memory it was not given: the
 * encoders write into a caller buffer of stated capacity and return the byte
 * count or a negative OB_SCS_E_* code; the parser reads at most the stated
 * input length and points into the caller's buffer for the parameters. That
 * keeps it usable from the 1 kHz bus engine with a fixed UART buffer.
 */
#ifndef OB_SCS_H
#define OB_SCS_H

#include <stddef.h>
#include <stdint.h>

/* Instructions used by the drivers. */
#define OB_SCS_INSTR_PING 0x01u
#define OB_SCS_INSTR_READ 0x02u
#define OB_SCS_INSTR_WRITE 0x03u
#define OB_SCS_INSTR_SYNC_WRITE 0x83u

/* Addresses every servo listens to; broadcast requests get no reply except ping. */
#define OB_SCS_BROADCAST_ID 0xFEu
/* Highest ID a single servo can carry (0xFF would read as a header byte). */
#define OB_SCS_MAX_SERVO_ID 0xFDu

/* Header (2) + ID + LEN + CODE + CHECKSUM: a frame with no parameters. */
#define OB_SCS_FRAME_OVERHEAD 6u
/* LEN is one byte and counts CODE and CHECKSUM, so at most 253 parameters. */
#define OB_SCS_MAX_PARAMS 253u
#define OB_SCS_MAX_FRAME (OB_SCS_FRAME_OVERHEAD + OB_SCS_MAX_PARAMS)

/*
 * Status-reply error flags. Bits 4, 6 and 7 carry no documented meaning on
 * the SCS/STS series; ob_scs_flag_name() returns NULL for them.
 */
#define OB_SCS_FLAG_VOLTAGE 0x01u     /* supply outside the configured voltage window */
#define OB_SCS_FLAG_ANGLE 0x02u       /* magnetic angle sensor fault */
#define OB_SCS_FLAG_OVERHEAT 0x04u    /* above the over-temperature limit */
#define OB_SCS_FLAG_OVERCURRENT 0x08u /* phase current above the protection limit */
#define OB_SCS_FLAG_OVERLOAD 0x20u    /* sustained load above the protection limit */

/*
 * STS memory table (little-endian 16-bit values, low byte at the lower address). The one list of
 * the registers the runtime, the simulator's emulated servos and the host tools use: both bindings
 * export each as scs.REG_<NAME>.
 */
#define OB_SCS_REG_ID 0x05u
#define OB_SCS_REG_RESPONSE_LEVEL 0x08u   /* 0: only PING and READ are answered, 1: every request */
#define OB_SCS_REG_MIN_ANGLE 0x09u        /* angle limits, steps; min and max both 0 = multi-turn */
#define OB_SCS_REG_MAX_ANGLE 0x0Bu
#define OB_SCS_REG_MAX_TORQUE 0x10u       /* EEPROM torque ceiling, 0.1 % of stall */
#define OB_SCS_REG_MODE 0x21u             /* OB_SCS_MODE_* */
#define OB_SCS_REG_TORQUE_ENABLE 0x28u    /* 1 enable, 0 coast */
#define OB_SCS_REG_ACCELERATION 0x29u     /* 100 steps/s^2; 0 = as fast as the motor can */
#define OB_SCS_REG_GOAL_POSITION 0x2Au    /* sign-magnitude, bit 15; a relative step in step mode */
#define OB_SCS_REG_GOAL_TIME 0x2Cu        /* in duty mode the signed duty, 0.1 %, sign bit 10 */
#define OB_SCS_REG_GOAL_SPEED 0x2Eu       /* sign-magnitude, bit 15, steps/s */
#define OB_SCS_REG_TORQUE_LIMIT 0x30u     /* 0.1 % of stall */
#define OB_SCS_REG_LOCK 0x37u             /* 0 lets EEPROM writes (such as a new ID) persist */
#define OB_SCS_REG_PRESENT_POSITION 0x38u /* sign-magnitude, bit 15; steps still to go in step mode */
#define OB_SCS_REG_PRESENT_SPEED 0x3Au    /* sign-magnitude, bit 15, steps/s */
#define OB_SCS_REG_PRESENT_LOAD 0x3Cu     /* sign-magnitude, bit 10, 0.1 % of stall */
#define OB_SCS_REG_PRESENT_VOLTAGE 0x3Eu  /* 0.1 V */
#define OB_SCS_REG_PRESENT_TEMPERATURE 0x3Fu /* degrees C */
#define OB_SCS_REG_MOVING 0x42u           /* 1 while the shaft turns */
#define OB_SCS_REG_PRESENT_CURRENT 0x45u  /* sign-magnitude, bit 15 */
/* Registers an emulated servo keeps: the table up to the last one above. */
#define OB_SCS_REG_COUNT 0x50u

/* Operating modes (REG_MODE). */
#define OB_SCS_MODE_POSITION 0u /* to the goal position inside one turn (multi-turn with both limits 0) */
#define OB_SCS_MODE_WHEEL 1u    /* the goal speed, under the acceleration register */
#define OB_SCS_MODE_DUTY 2u     /* open loop: the duty in REG_GOAL_TIME */
#define OB_SCS_MODE_STEP 3u     /* a relative step of REG_GOAL_POSITION, then holding */

/* Encoder steps per output turn (ST-3215, ST-3032). */
#define OB_SCS_COUNTS_PER_REV 4096u
/* Present position in the multi-turn modes: a sign-magnitude window of +-32767 steps that wraps. */
#define OB_SCS_MULTI_TURN_SPAN 65535u

/* Where the direction bit sits in each sign-magnitude register. */
#define OB_SCS_POSITION_SIGN_BIT 15u
#define OB_SCS_SPEED_SIGN_BIT 15u
#define OB_SCS_LOAD_SIGN_BIT 10u
#define OB_SCS_DUTY_SIGN_BIT 10u

/* Encoder failures (negative so they never collide with a byte count). */
typedef enum {
    OB_SCS_E_NULL = -1,     /* a required pointer was NULL */
    OB_SCS_E_BUFFER = -2,   /* the output capacity is smaller than the packet */
    OB_SCS_E_ID = -3,       /* ID not addressable by this instruction */
    OB_SCS_E_LENGTH = -4,   /* zero data length, or parameters past OB_SCS_MAX_PARAMS */
    OB_SCS_E_REGISTER = -5, /* register + length runs past address 0xFF */
} ob_scs_error_t;

/* Human-readable text for an OB_SCS_E_* code, for error messages. */
const char *ob_scs_strerror(int code);

/* ~(sum of bytes) & 0xFF over ID..last parameter. */
uint8_t ob_scs_checksum(const uint8_t *bytes, size_t n);

/*
 * Any frame: id, code (instruction or error flags) and n parameters. IDs up
 * to 0xFE are accepted; this is the building block of the encoders below and
 * the way to send instructions they do not name (REG_WRITE, ACTION, ...).
 */
int ob_scs_encode_frame(uint8_t id, uint8_t code, const uint8_t *params, size_t n, uint8_t *out,
                        size_t cap);

/* PING. The broadcast ID is allowed: a lone servo on the bus answers it with its ID. */
int ob_scs_encode_ping(uint8_t id, uint8_t *out, size_t cap);

/* READ n bytes from reg. A servo ID is required: only a unicast read is answered. */
int ob_scs_encode_read(uint8_t id, uint8_t reg, uint8_t n, uint8_t *out, size_t cap);

/* WRITE n bytes to reg (broadcast allowed: every servo applies it, none replies). */
int ob_scs_encode_write(uint8_t id, uint8_t reg, const uint8_t *data, size_t n, uint8_t *out, size_t cap);

/*
 * SYNC WRITE: one broadcast packet that gives each of count servos its own
 * data_len bytes at reg, so they all apply their setpoints at the same packet
 * boundary. data holds count rows of data_len bytes, in the order of ids.
 */
int ob_scs_encode_sync_write(uint8_t reg, uint8_t data_len, const uint8_t *ids, const uint8_t *data,
                             size_t count, uint8_t *out, size_t cap);

/* A servo's status reply (what a simulated servo sends back). */
int ob_scs_encode_status(uint8_t id, uint8_t error_flags, const uint8_t *params, size_t n, uint8_t *out,
                         size_t cap);

/* Outcome of parsing the front of a receive buffer. */
typedef enum {
    OB_SCS_PARSE_OK = 0,           /* a whole, checksummed frame */
    OB_SCS_PARSE_NEED_MORE = 1,    /* no complete frame yet: read more bytes */
    OB_SCS_PARSE_BAD_CHECKSUM = 2, /* a complete frame whose checksum does not match */
    OB_SCS_PARSE_BAD_HEADER = 3,   /* a frame from an ID that cannot send it (a reply from 0xFE) */
    OB_SCS_PARSE_BAD_LENGTH = 4,   /* LEN below 2: no room for CODE and CHECKSUM */
    OB_SCS_PARSE_BAD_ARGUMENT = 5, /* NULL buffer with a non-zero length, or NULL out */
} ob_scs_parse_t;

typedef struct {
    /*
     * Bytes the caller should drop from the front of its buffer before the
     * next parse: garbage before the header plus the frame on OK; garbage plus
     * the first header byte on a rejected frame (so the next parse rescans
     * the rest and resynchronises on a real header inside it); the garbage
     * proven not to start a frame on NEED_MORE.
     */
    size_t consumed;
    /* On NEED_MORE: at least this many more bytes are needed (0 otherwise). */
    size_t needed;
    uint8_t id;
    uint8_t code;           /* instruction (request) or error flags (status reply) */
    const uint8_t *params;  /* inside the caller's buffer; NULL when param_len is 0 */
    size_t param_len;
} ob_scs_frame_t;

/*
 * Find and check the first frame in buf[0..len). Leading garbage is skipped,
 * runs of 0xFF before the ID count as preamble, and nothing at or past
 * buf + len is ever read. Frames addressed to 0xFE (broadcast requests) are
 * accepted.
 */
ob_scs_parse_t ob_scs_parse_frame(const uint8_t *buf, size_t len, ob_scs_frame_t *frame);

/* As ob_scs_parse_frame, for servo replies: a frame from 0xFE is BAD_HEADER. */
ob_scs_parse_t ob_scs_parse_status(const uint8_t *buf, size_t len, ob_scs_frame_t *status);

/* Name of one status flag bit (0..7), or NULL for a bit with no documented meaning. */
const char *ob_scs_flag_name(unsigned bit);

/*
 * Sign-magnitude registers: bit sign_bit (1..15) is the direction, the bits
 * below it the magnitude. Encoding saturates the magnitude at what those bits
 * hold; decoding ignores any bits above the sign bit.
 */
uint16_t ob_scs_sm_encode(int32_t value, unsigned sign_bit);
int32_t ob_scs_sm_decode(uint16_t raw, unsigned sign_bit);

/* Little-endian 16-bit register values as the SCS/STS memory table stores them. */
static inline void ob_scs_put_u16(uint8_t *p, uint16_t value) {
    p[0] = (uint8_t)(value & 0xFFu);
    p[1] = (uint8_t)(value >> 8);
}

static inline uint16_t ob_scs_get_u16(const uint8_t *p) {
    return (uint16_t)(p[0] | ((uint16_t)p[1] << 8));
}

#endif /* OB_SCS_H */
